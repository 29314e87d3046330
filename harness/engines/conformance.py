"""The conformance kit an adapter author runs: ``check_engine(MyEngine)`` -> ``[]`` when the
adapter keeps the engine contract (:mod:`harness.engines.contract`), else one line per
broken promise.

What it checks, on the hand-built reference scenes (:func:`harness.scene.reference_scenes`)
under each preset role:

* the class attributes the rest of the harness reads are present and well formed (name,
  version, presets with the same keys as ``setting_docs``, description, per-preset why,
  plot style, speed caps, timing, calibration knobs or why there are none);
* settings: each preset resolves and validates, also at every value of a calibration knob;
  an unknown key and a non-positive time step are refused with
  :class:`EngineSettingsError`;
* runs: every scene the engine supports ends separated (no blow-up, no missing contact, no
  step cap; a multi-contact or out-of-plane status is a finding, not a fault), reports at
  least one contact, with finite velocities; ``run_many`` of the scenes equals ``run`` of
  each bit for bit (rerun against rerun on one machine), and a second ``run`` equals the
  first (fresh per-run state).
A scene the engine refuses with :class:`UnsupportedScene` is skipped, not failed.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from harness.engines import load_engine
from harness.engines.contract import Engine, Status, StepTiming, UnsupportedScene
from harness.engines.settings import EngineSettingsError
from harness.scene.reference import reference_scenes

# Statuses that break the contract on a reference scene; the others (multi-contact,
# out-of-plane) are findings about the engine that the verdicts flag, not adapter faults.
_BROKEN = (Status.BLOW_UP, Status.NO_CONTACT, Status.NO_SEPARATION)
# The preset roles every engine has (the registry's PRESET_ROLES, which imports this layer).
_ROLES = ("defaults", "accurate")
# What an engine may declare as its own law (the accuracy bench measures against it): a law
# the bench solves, or "converged" (its own run at the finest settings).
_OWN_LAWS = ("newton-lcp", "poisson", "stronge", "converged")


def check_engine(engine: type[Engine] | Engine | str) -> list[str]:
    """The contract's promises ``engine`` (a class, an instance or a registered name)
    breaks, one line each; an empty list when it conforms."""
    if isinstance(engine, str):
        instance = load_engine(engine)
    elif isinstance(engine, type):
        instance = engine()
    else:
        instance = engine
    failures = _attribute_failures(type(instance))
    if failures:  # runs need well-formed presets
        return failures
    failures += _settings_failures(instance)
    failures += _run_failures(instance)
    return failures


def _attribute_failures(cls: type[Engine]) -> list[str]:
    failures = []
    where = f"{cls.__name__}"
    if not (isinstance(cls.name, str) and cls.name):
        failures.append(f"{where}.name: a non-empty string, got {cls.name!r}")
    if not isinstance(cls.version, str):
        failures.append(f"{where}.version: a string, got {cls.version!r}")
    docs = cls.setting_docs
    if not (isinstance(docs, Mapping) and all(isinstance(v, str) and v for v in docs.values())):
        failures.append(f"{where}.setting_docs: a mapping of key -> one line of text")
    elif not {"time_step", "max_steps", "approach_steps"} <= set(docs):
        failures.append(f"{where}.setting_docs: lacks a common key "
                        "(time_step, max_steps, approach_steps)")
    presets = cls.presets
    if not isinstance(presets, Mapping) or set(presets) != set(_ROLES):
        failures.append(f"{where}.presets: exactly {list(_ROLES)}, got "
                        f"{list(presets) if isinstance(presets, Mapping) else presets!r}")
    elif isinstance(docs, Mapping):
        for role, values in presets.items():
            if set(values) != set(docs):
                failures.append(f"{where}.presets[{role!r}]: keys differ from setting_docs "
                                f"by {sorted(set(values) ^ set(docs))}")
    if not (isinstance(cls.description, str) and cls.description.strip()):
        failures.append(f"{where}.description: one paragraph of text, got {cls.description!r}")
    why = cls.preset_why
    if not (isinstance(why, Mapping) and set(why) <= set(_ROLES)
            and all(isinstance(v, str) and v for v in why.values())):
        failures.append(f"{where}.preset_why: role -> one line, roles among {list(_ROLES)}, "
                        f"got {why!r}")
    style = cls.plot_style
    if not (isinstance(style, tuple) and len(style) == 2
            and all(isinstance(v, str) and v for v in style)):
        failures.append(f"{where}.plot_style: (colour, marker) strings, got {style!r}")
    caps = cls.speed_caps
    if caps is not None and not (
            isinstance(caps, tuple) and len(caps) == 2
            and all(isinstance(v, float) and math.isfinite(v) and v > 0 for v in caps)):
        failures.append(f"{where}.speed_caps: None or (linear m/s, angular rad/s) positive "
                        f"finite floats, got {caps!r}")
    if not (isinstance(cls.rounding, float) and 0.0 < cls.rounding < 1e-3):
        failures.append(f"{where}.rounding: a float in (0, 1e-3), got {cls.rounding!r}")
    statuses = cls.reference_statuses
    if not (isinstance(statuses, Mapping) and all(
            isinstance(key, tuple) and len(key) == 2 and key[1] in _ROLES
            and value in set(Status) for key, value in statuses.items())):
        failures.append(f"{where}.reference_statuses: (scene, role) -> a status, got "
                        f"{statuses!r}")
    if not isinstance(cls.own_law, str) or cls.own_law not in _OWN_LAWS:
        failures.append(f"{where}.own_law: one of {list(_OWN_LAWS)}, got {cls.own_law!r}")
    left_out = cls.survey_left_out
    if not (isinstance(left_out, Mapping) and set(left_out) <= set(_ROLES)
            and all(isinstance(v, str) and v for v in left_out.values())):
        failures.append(f"{where}.survey_left_out: role -> why, roles among {list(_ROLES)}, "
                        f"got {left_out!r}")
    impacts = cls.bench_impacts
    if not (isinstance(impacts, tuple) and len(impacts) == 2
            and all(isinstance(v, int) and v > 0 for v in impacts)):
        failures.append(f"{where}.bench_impacts: (quick, full) positive ints, got {impacts!r}")
    if not isinstance(cls.timing, StepTiming):
        failures.append(f"{where}.timing: a StepTiming, got {cls.timing!r}")
    knobs = cls.calibration_knobs
    if not (isinstance(knobs, tuple) and all(
            isinstance(knob, tuple) and len(knob) == 2 and isinstance(docs, Mapping)
            and knob[0] in docs and isinstance(knob[1], tuple) and len(knob[1]) >= 2
            for knob in knobs)):
        failures.append(f"{where}.calibration_knobs: ((setting of setting_docs, (two or more "
                        f"values)), ...), got {knobs!r}")
    if not knobs and not (isinstance(cls.no_calibration_knobs_why, str)
                          and cls.no_calibration_knobs_why.strip()):
        failures.append(f"{where}.no_calibration_knobs_why: one line of text, got "
                        f"{cls.no_calibration_knobs_why!r}")
    return failures


def _settings_failures(engine: Engine) -> list[str]:
    failures = []
    for role in _ROLES:
        try:
            resolved = engine.settings(role)
            engine.validate_settings(resolved)
        except (ValueError, TypeError) as error:
            failures.append(f"settings({role!r}) fails: {error}")
            continue
        for bad, what in (({"no-such-setting": 1}, "an unknown key"),
                          ({"time_step": -1.0}, "a negative time_step")):
            try:
                engine.settings(role, bad)
            except EngineSettingsError:
                continue
            except Exception as error:  # noqa: BLE001 - the kit reports any wrong exception
                failures.append(f"settings({role!r}, {bad}) raises {type(error).__name__}, "
                                "not EngineSettingsError")
                continue
            failures.append(f"settings({role!r}, {bad}) accepts {what}")
        for knob, values in engine.calibration_knobs:  # every value calibrate may try
            for value in values:
                try:
                    engine.validate_settings(engine.settings(role, {knob: value}))
                except (ValueError, TypeError) as error:
                    failures.append(f"calibration_knobs: settings({role!r}, {{{knob!r}: "
                                    f"{value!r}}}) fails: {error}")
    return failures


def _run_failures(engine: Engine) -> list[str]:
    failures = []
    scenes = [scene for scene, _, _ in reference_scenes().values()]
    for role in _ROLES:
        settings = engine.settings(role)
        runs, supported = [], []
        for scene in scenes:
            label = f"run({scene.name!r}, preset {role!r})"
            try:
                run = engine.run(scene, settings)
            except UnsupportedScene:
                continue
            except Exception as error:  # noqa: BLE001 - the kit reports, it does not stop
                failures.append(f"{label} raises {type(error).__name__}: {error}")
                continue
            supported.append(scene)
            runs.append(run)
            if run.status in _BROKEN or not run.separated:
                failures.append(f"{label}: status {run.status} ({run.status_reason}), "
                                f"separated {run.separated}; expected a separation")
            if not run.contacts:
                failures.append(f"{label}: no contact reported")
            if (run.out_of_plane_drift is None) is not engine.native_2d:
                failures.append(f"{label}: out_of_plane_drift {run.out_of_plane_drift!r} "
                                f"but native_2d is {engine.native_2d}")
            if not all(math.isfinite(v) for body in run.velocities for v in body):
                failures.append(f"{label}: non-finite velocities {run.velocities}")
            if engine.run(scene, settings) != run:
                failures.append(f"{label}: a second run differs from the first")
        if not supported:
            failures.append(f"preset {role!r}: the engine supports none of the reference "
                            "scenes")
            continue
        try:
            batched = engine.run_many(supported, settings)
        except Exception as error:  # noqa: BLE001
            failures.append(f"run_many(preset {role!r}) raises {type(error).__name__}: {error}")
            continue
        for scene, one, many in zip(supported, runs, batched, strict=True):
            if one != many:
                failures.append(f"run_many(preset {role!r}): scene {scene.name!r} differs "
                                "from run() (not bit for bit)")
    return failures


__all__ = ["check_engine"]
