"""``impact-harness findings``: the README's findings on the laws, and the numbers it states.

Without options it measures the findings (:func:`harness.report.findings.measure`) and prints
them as Markdown tables. ``--check`` recomputes every number the README and ``docs/`` state
about results (marked in the text, :mod:`harness.report.stated`) and lists those that differ
(exit 1); ``--write`` rewrites them in place. The command sits above both modules, since the
stated numbers include the findings' own.
"""

from __future__ import annotations

import argparse
import sys

from harness.report import stated
from harness.report.findings import markdown, measure


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--count", type=int, default=100_000,
                        help="random problems to draw (default: 100000)")
    parser.add_argument("--seed", type=int, default=2009, help="random seed (default: 2009)")
    what = parser.add_mutually_exclusive_group()
    what.add_argument("--check", action="store_true",
                      help="recompute every number README.md and docs/ state about results "
                           "and list those that differ (exit 1)")
    what.add_argument("--write", action="store_true",
                      help="recompute them and write them into the texts")
    parser.add_argument("--only", action="append", metavar="SOURCE",
                        help="with --check or --write: only this source of numbers "
                             "(repeatable; e.g. findings, table3, two-contacts, flat-landings, "
                             "library)")


def main(args) -> int:
    if not (args.check or args.write):
        if args.only:
            print("impact-harness findings: --only needs --check or --write", file=sys.stderr)
            return 2
        print(markdown(measure(args.count, args.seed)), end="")
        return 0

    unknown = sorted(set(args.only or ()) - set(stated.SOURCES))
    if unknown:
        print(f"impact-harness findings: --only {unknown[0]}: not a source of stated numbers "
              f"(allowed: {', '.join(stated.SOURCES)})", file=sys.stderr)
        return 2
    skipped: dict[str, str] = {}
    try:
        wrong = stated.check(write=args.write, only=args.only, skipped=skipped)
    except ValueError as error:  # a malformed marker in a text
        print(f"impact-harness findings: {error}", file=sys.stderr)
        return 2
    for source, why in skipped.items():  # its inputs are not here (the Fazeli drops)
        print(f"impact-harness findings: {source}: not checked: {why}", file=sys.stderr)
    for line in wrong:
        print(line)
    if not wrong:
        print("every stated number agrees with the command that produces it"
              + (" (texts rewritten where they differed)" if args.write else ""))
    return 1 if wrong else 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="python -m harness.report.findings_command",
                                     description=__doc__)
    add_arguments(parser)
    raise SystemExit(main(parser.parse_args()))


__all__ = ["add_arguments", "main"]
