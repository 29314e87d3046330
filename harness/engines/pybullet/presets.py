"""pybullet's settings: their docs, the defaults (``None``: Bullet's own) and the two
presets, and the ``setPhysicsEngineParameter`` keyword each engine parameter sets."""

from __future__ import annotations

# setting key -> pybullet setPhysicsEngineParameter keyword
_ENGINE_PARAMETERS: dict[str, str] = {
    "time_step": "fixedTimeStep",
    "num_solver_iterations": "numSolverIterations",
    "num_sub_steps": "numSubSteps",
    "contact_breaking_threshold": "contactBreakingThreshold",
    "contact_erp": "contactERP",
    "erp": "erp",
    "friction_erp": "frictionERP",
    "contact_slop": "contactSlop",
    "restitution_velocity_threshold": "restitutionVelocityThreshold",
    "enable_cone_friction": "enableConeFriction",
    "solver_residual_threshold": "solverResidualThreshold",
    "warm_starting_factor": "warmStartingFactor",
    "global_cfm": "globalCFM",
    "use_split_impulse": "useSplitImpulse",
}

SETTING_DOCS: dict[str, str] = {
    "time_step": "s, fixedTimeStep (default 1/240)",
    "num_solver_iterations": "numSolverIterations, PGS iterations per step (default 50)",
    "num_sub_steps": "numSubSteps, sub-steps per step (default 0 = none)",
    "contact_breaking_threshold": "m, contactBreakingThreshold: contacts exist up to this gap "
    "(default 0.02; process-wide in Bullet, set before every run)",
    "contact_erp": "contactERP, fraction of penetration corrected per step by velocity "
    "(default 0.2)",
    "erp": "erp, joint error reduction (default 0.2; the planar chain's joints are exact)",
    "friction_erp": "frictionERP (default 0.2)",
    "contact_slop": "m, contactSlop, penetration left uncorrected (default 1e-5)",
    "restitution_velocity_threshold": "m/s, restitution is 0 below this approach speed "
    "(default 0.2)",
    "enable_cone_friction": "enableConeFriction, 1 = implicit cone, 0 = two-direction box "
    "(default 1)",
    "solver_residual_threshold": "solverResidualThreshold, PGS stops below it (default 1e-7)",
    "warm_starting_factor": "warmStartingFactor, share of last step's impulse re-applied "
    "(default 0.85)",
    "global_cfm": "globalCFM, constraint force mixing (default 0)",
    "use_split_impulse": "useSplitImpulse, 1 = position correction apart (rigid bodies; default 1)",
    "linear_damping": "1/s, per-link linearDamping (Bullet's default 0.04)",
    "angular_damping": "1/s, per-link angularDamping (Bullet's default 0.04)",
    "max_steps": "step cap; reported as status no-separation when hit in contact",
    "approach_steps": "steps of free flight before first touch (0 = touching at the first step)",
}

_DEFAULTS = {key: None for key in _ENGINE_PARAMETERS}
_DEFAULTS.update(
    time_step=1.0 / 240.0,
    # Set explicitly: a process-wide global in Bullet, so "not set" would inherit another run's.
    contact_breaking_threshold=0.02,
    linear_damping=0.04,
    angular_damping=0.04,
    max_steps=1000,
    approach_steps=0.0,
)
PRESETS: dict[str, dict] = {
    "defaults": dict(_DEFAULTS),
    "accurate": dict(
        _DEFAULTS,
        # Coupled contacts (the rod) need >= 10 iterations; 100 with no early exit reaches
        # rounding on every test scene.
        num_solver_iterations=100,
        solver_residual_threshold=0.0,
        contact_breaking_threshold=1e-6,  # no early contact (and no gap/dt bias)
        contact_erp=0.0,
        friction_erp=0.0,
        contact_slop=0.0,
        restitution_velocity_threshold=0.0,
        warm_starting_factor=0.0,  # no impulse carried from a previous step
        linear_damping=0.0,
        angular_damping=0.0,
    ),
}

_RUN_ONLY = ("max_steps", "approach_steps")
