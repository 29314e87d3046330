"""The ``impact-harness`` command line.

Each command lives in its own module, which provides ``add_arguments(parser)`` and
``main(args) -> int``. Only the chosen command's module is imported, so ``impact-harness
paper`` never pays for importing an engine or a plotting library it does not use.
"""

from __future__ import annotations

import argparse
import importlib
import sys

# command name -> (module, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "suite": ("harness.run.suite", "the validation suite (`make validate`): paper, run, report"),
    "paper": ("harness.report.table3", "reproduce the paper's Table 3 into reports/paper-table3.md"),
    "run": ("harness.run.runner", "run scenarios through every law and engine, write results"),
    "report": ("harness.report", "write reports/index.html and reports/summary.md from results"),
    "compare": ("harness.report.compare",
                "compare two results files; exit 1 when a change exceeds --fail-above"),
    "validate": ("harness.scenarios.cli", "check scenario files"),
    "new": ("harness.scenarios.cli", "write a commented starting scenario file"),
    "bench": ("harness.bench.solver", "benchmarks: solver throughput, engine overhead, speed-accuracy"),
    "stress": ("harness.stress", "numerical stress of the solver and the engines"),
    "findings": ("harness.report.findings", "re-measure the README's findings on the laws"),
    "survey": ("harness.survey.cli", "departure distributions over families of impacts"),
}


def build_parser(command: str | None) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="impact-harness",
        description="Validation harness for planar rigid-body impact with friction.",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (module_name, help_text) in COMMANDS.items():
        sub = subparsers.add_parser(name, help=help_text, description=help_text)
        if name == command:
            module = importlib.import_module(module_name)
            add = getattr(module, f"add_{name}_arguments", None) or module.add_arguments
            add(sub)
            sub.set_defaults(handler=getattr(module, f"main_{name}", None) or module.main)
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    command = next((arg for arg in argv if not arg.startswith("-")), None)
    parser = build_parser(command if command in COMMANDS else None)
    args = parser.parse_args(argv)
    if getattr(args, "handler", None) is None:
        parser.print_help()
        return 2
    return int(args.handler(args) or 0)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
