"""The Kharaz et al. (2001) curves through the engines: the disk of ``kharaz`` as a scene
(a realistic alumina mass, 2.6e-4 kg; I = 2/5 m r²), every incidence run by an engine under
a preset, each run judged as the suite judges it (harness/run/verdicts/) before its
numbers count: a flagged run is returned with its reason and NaN curves."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from harness.run import verdicts
from harness.scene.geometry import impact_problem, scene_contact
from harness.scene.model import Body, Disk, Scene

from . import kharaz

DENSITY = 3950.0  # kg/m³, alumina


@dataclass(frozen=True)
class EngineCurves:
    engine: str
    preset: str
    incidence_deg: np.ndarray
    tangential_restitution: np.ndarray  # NaN where the run is flagged
    rebound_deg: np.ndarray
    spin: np.ndarray  # forward spin, rad/s
    verdicts: tuple[str, ...]  # "ok" or the first failing check's name, per incidence


def scene(incidence_deg: float):
    radius = kharaz.RADIUS
    mass = DENSITY * 4.0 / 3.0 * math.pi * radius**3
    angle = math.radians(incidence_deg)
    velocity = (kharaz.SPEED * math.sin(angle), -kharaz.SPEED * math.cos(angle))
    body = Body("sphere", Disk(radius), mass, (0.0, radius), 0.0, velocity, 0.0,
                inertia=0.4 * mass * radius**2)
    return Scene((body,), kharaz.E, kharaz.MU, ground=True, name=f"kharaz-{incidence_deg:g}")


def judged(run, scene_) -> str:
    """"ok" for a run judged a single impact, else the first failing check's name."""
    if not np.all(np.isfinite(np.asarray(run.u_after, dtype=float))):
        return "non-finite"
    contact = scene_contact(scene_)
    problem = impact_problem(scene_, contact.point, contact.normal)
    law = problem.solve(mu=scene_.friction, e=scene_.restitution, law="newton-lcp")
    verdict = verdicts.judge(scene_, problem, verdicts.numbers_from_run(run),
                             law_energy_change=float(law.energy_change))
    return "ok" if verdict.single_impact else verdict.names[0]


def engine_curves(engine, preset: str, incidence_deg) -> EngineCurves:
    """``engine`` (a loaded :class:`harness.engines.contract.Engine`) under ``preset`` at
    every incidence."""
    angles = np.atleast_1d(np.asarray(incidence_deg, dtype=float))
    scenes = [scene(float(a)) for a in angles]
    runs = engine.run_many(scenes, preset=preset)
    names = tuple(judged(run, s) for run, s in zip(runs, scenes))
    after = np.array([np.asarray(run.u_after, dtype=float)[:3] for run in runs])
    after[np.array(names) != "ok"] = np.nan
    before_x = kharaz.SPEED * np.sin(np.radians(angles))
    return EngineCurves(engine.name, preset, angles, after[:, 0] / before_x,
                        np.degrees(np.arctan2(after[:, 0], after[:, 1])), -after[:, 2], names)
