"""``impact-harness calibrate ENGINE --to data|LAW``: an engine's own knobs fitted by a small
grid (:mod:`harness.experiments.calibrate`)."""

from __future__ import annotations

import argparse
import sys

import planar_impact as pi
from harness import bounds
from harness.engines import (
    EngineNotInstalled,
    engine_names,
    load_engine,
    preset_label,
    preset_role,
)
from harness.store.cache import ResultCache

from . import cached, calibrate, drops_engines, fazeli, frames, registry


def add_arguments(parser: argparse.ArgumentParser) -> None:
    # the engines registered when the command line is parsed (run-time ones too)
    parser.add_argument("engine", choices=engine_names(),
                        help="the engine whose settings are fitted")
    parser.add_argument("--to", required=True, choices=("data", *pi.LAWS),
                        help="the target: the Fazeli drops (data) or a law on a population "
                             "of ellipse drops")
    parser.add_argument("--preset", default=None, help="one preset (default: every preset)")
    parser.add_argument("--data", metavar="DIR", default=None,
                        help=f"the Fazeli files (default: ${registry.FAZELI_2017.env_var})")
    parser.add_argument("--grid", choices=sorted(calibrate.PAIR_GRIDS), default="quick",
                        help="the (mu, e) values tried, beside the engine's own knobs: "
                             + "; ".join(f"{name}: mu {_values(mus)}, e {_values(es)}"
                                         for name, (mus, es) in calibrate.PAIR_GRIDS.items())
                             + " (default quick)")
    parser.add_argument("--drops", type=bounds.option("drops"), default=12,
                        help="impacts scored per cell (default 12): a random sample of the "
                             "data's drops, or of a generated population, drawn with --seed")
    parser.add_argument("--seed", type=bounds.option("seed"), default=0,
                        help="seed of that sample, of the bootstrap's resamples and of the "
                             "held-out split (default 0; printed with the result)")
    parser.add_argument("--replicates", type=bounds.option("replicates"),
                        default=calibrate.REPLICATES,
                        help="bootstrap resamples of the scored drops behind the intervals "
                             f"(default {calibrate.REPLICATES})")
    parser.add_argument("--law-mu", type=bounds.option("law-mu"), default=0.3,
                        help="--to LAW: the law's mu (default 0.3, a cell of the quick grid)")
    parser.add_argument("--law-e", type=bounds.option("law-e"), default=0.6,
                        help="--to LAW: the law's e (default 0.6, a cell of the quick "
                             "grid)")
    parser.add_argument("--no-cache", action="store_true",
                        help="compute again (by default a rerun with the same data, code, "
                             "installed versions and options reads the result cache)")


def _values(values) -> str:
    return ", ".join(f"{value:g}" for value in values)


def main(args) -> int:
    # Every count and setting was bounded by its argparse type (harness.bounds.option)
    # before this runs: ``--drops 100000000`` once grew to 23.8 GB.
    if args.data is not None and args.to != "data":
        print(f"impact-harness calibrate: --data {args.data}: read only with --to data (here "
              f"--to {args.to}, a generated population)", file=sys.stderr)
        return 2
    try:
        engine = load_engine(args.engine)
    except EngineNotInstalled as missing:
        print(f"impact-harness calibrate: {args.engine}: not installed: {missing}",
              file=sys.stderr)
        return 2
    presets = list(engine.presets)
    if args.preset is not None:  # the name users see (mujoco's matched-bounce) selects its role
        try:
            role = preset_role(engine.name, args.preset)
        except ValueError:
            role = None
        if role not in engine.presets:
            allowed = ", ".join(preset_label(engine.name, name) for name in engine.presets)
            print(f"impact-harness calibrate: --preset {args.preset}: allowed: {allowed}",
                  file=sys.stderr)
            return 2
        presets = [role]
    cache = None if args.no_cache else ResultCache()
    problem = cached.cache_problem(cache)
    if problem is not None:
        print(f"impact-harness calibrate: the cache {cache.root}: {problem} (or --no-cache)",
              file=sys.stderr)
        return 2
    data_sha256 = None
    if args.to == "data":
        try:
            data = fazeli.load(registry.locate(registry.FAZELI_2017, args.data))
            data_sha256 = data.hashes
        except registry.DataMissing as missing:
            print(f"impact-harness calibrate: --to data: {missing}", file=sys.stderr)
            return 2
        except registry.DataInvalid as invalid:
            print(f"impact-harness calibrate: {invalid}", file=sys.stderr)
            return 2
        target = frames.in_frame(data.impacts, frames.DEFAULT_FRAME)  # experiments' frame
        rows = calibrate.sample_rows(len(target), args.drops, args.seed)
        impacts = target.subset(rows)
        thetas, _ = drops_engines.jacobian_angles(impacts, data.pre_impact_angles[rows])
        sample = {"drops": len(rows), "of": len(target), "seed": args.seed}
    else:
        impacts, thetas = calibrate.drop_population(args.drops, seed=args.seed)
        sample = {"drops": args.drops, "of": "a generated population", "seed": args.seed}
    progress = cached.Progress("impact-harness calibrate")
    settings = {"engine": engine.name, "to": args.to, "grid": args.grid, "drops": args.drops,
                "seed": args.seed, "replicates": args.replicates, "law_mu": args.law_mu,
                "law_e": args.law_e}
    for preset in presets:
        def compute(preset=preset) -> dict:
            print(calibrate.summary(calibrate.calibrate(
                engine, preset, impacts, thetas, args.to, args.grid, args.law_mu, args.law_e,
                sample, replicates=args.replicates, seed=args.seed, progress=progress.step)))
            return {}

        progress(f"{engine.name} ({preset_label(engine.name, preset)})")
        cached.printed_once(cache, cached.payload("calibrate", {**settings, "preset": preset},
                                                  data_sha256), compute, progress)
    return 0
