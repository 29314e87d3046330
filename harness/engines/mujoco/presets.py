"""MuJoCo's settings: their docs, the defaults, the two presets, and the MuJoCo enums the
settings name (integrator, friction cone, solver)."""

from __future__ import annotations

import mujoco

SETTING_DOCS: dict[str, str] = {
    "time_step": "s, opt.timestep (default 0.002)",
    "integrator": "opt.integrator: Euler | implicit | implicitfast | RK4 (default Euler)",
    "cone": "opt.cone: pyramidal | elliptic (default pyramidal)",
    "solver": "opt.solver: Newton | CG | PGS (default Newton)",
    "iterations": "opt.iterations (default 100)",
    "tolerance": "opt.tolerance (default 1e-8)",
    "ls_iterations": "opt.ls_iterations, line-search iterations (default 50)",
    "noslip_iterations": "opt.noslip_iterations (default 0)",
    "noslip_tolerance": "opt.noslip_tolerance (default 1e-6)",
    "impratio": "opt.impratio, friction-to-normal impedance ratio (default 1)",
    "solref": "[timeconst s, dampratio] or direct [-stiffness, -damping], or \"restitution\": "
    "direct form from e and contact_steps (default [0.02, 1])",
    "contact_steps": "steps a contact lasts when solref is \"restitution\"",
    "solimp": "[dmin, dmax, width m, midpoint, power] (default [0.9, 0.95, 0.001, 0.5, 2])",
    "margin": "m, geom margin: contacts become active this far apart (default 0)",
    "max_steps": "step cap; reported as status no-separation when hit in contact",
    "approach_steps": "steps of free flight before first touch (0 = touching at the first step)",
}

_DEFAULTS = {
    "time_step": 0.002,
    "integrator": "Euler",
    "cone": "pyramidal",
    "solver": "Newton",
    "iterations": 100,
    "tolerance": 1e-8,
    "ls_iterations": 50,
    "noslip_iterations": 0,
    "noslip_tolerance": 1e-6,
    "impratio": 1.0,
    "solref": [0.02, 1.0],
    "contact_steps": 100,
    "solimp": [0.9, 0.95, 0.001, 0.5, 2.0],
    "margin": 0.0,
    "max_steps": 20000,
    "approach_steps": 0.0,
}
PRESETS: dict[str, dict] = {
    "defaults": dict(_DEFAULTS),
    "accurate": dict(
        _DEFAULTS,
        # RK4 over a 0.5 ms contact of 50 steps reproduces the unilateral spring-damper's
        # bounce to ~1e-5 (Euler's first-order error is ~0.5/contact_steps: -0.9% at e = 0.5
        # with 100 steps, -4% at e = 0.1), at the cost of Euler with ~100 steps.
        time_step=1e-5,
        integrator="RK4",
        solref="restitution",
        contact_steps=50,
        solimp=[0.9999, 0.9999, 0.001, 0.5, 2.0],
    ),
}

_INTEGRATORS = {
    "Euler": mujoco.mjtIntegrator.mjINT_EULER,
    "RK4": mujoco.mjtIntegrator.mjINT_RK4,
    "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
}
_CONES = {"pyramidal": mujoco.mjtCone.mjCONE_PYRAMIDAL, "elliptic": mujoco.mjtCone.mjCONE_ELLIPTIC}
_SOLVERS = {
    "Newton": mujoco.mjtSolver.mjSOL_NEWTON,
    "CG": mujoco.mjtSolver.mjSOL_CG,
    "PGS": mujoco.mjtSolver.mjSOL_PGS,
}
