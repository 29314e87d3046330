"""The ``impact-harness`` command line.

Each command lives in its own module, which provides ``add_arguments(parser)`` and
``main(args) -> int``. Only the chosen command's module is imported, so ``impact-harness
paper`` never pays for importing an engine or a plotting library it does not use.

Exit status of every command:

* 0 -- done, every check passed;
* 1 -- done, but a check failed: a scenario's ``[expect.gate]`` (``run``, ``suite``) or an
  unexplained Table 3 miss (``suite``);
* 2 -- bad input: an option, a scenario file (each bad file is one line naming the file,
  the key, the value and what is allowed; the good files are still processed) or a results
  file; nothing is written that the input could not support;
* 2 also when the machine refuses a write (a full disk, a read-only one, a quota: one
  line naming the file);
* 3 -- internal error: a bug in the harness (one line on stderr; set
  ``IMPACT_HARNESS_TRACEBACK=1`` for the traceback). Finished engine runs stay in the cache.

130 after Ctrl-C, as usual for a shell.
"""

from __future__ import annotations

import argparse
import errno
import importlib
import os
import sys
import traceback
from pathlib import Path

from harness import bounds
from harness.store.files import NotRegularFile

# command name -> (module, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "suite": ("harness.suite", "the validation suite (`make validate`): paper, run, report"),
    "paper": ("harness.report.table3",
              "reproduce the paper's Table 3 into reports/paper-table3.md"),
    "run": ("harness.run.command", "run scenarios through every law and engine, write results"),
    "report": ("harness.report", "write reports/index.html and reports/summary.md from results"),
    "compare": ("harness.report.compare",
                "compare two results files; exit 1 when a change exceeds --fail-above"),
    "export": ("harness.report.export",
               "the records as one tidy table, a row per run × law (CSV or Parquet)"),
    "validate": ("harness.validate", "check scenario files and population files"),
    "new": ("harness.scenarios.cli", "write a commented starting scenario file"),
    "bench": ("harness.bench.solver",
              "benchmarks: solver throughput, engine overhead, speed-accuracy"),
    "stress": ("harness.stress", "numerical stress of the solver and the engines"),
    "findings": ("harness.report.findings_command", "re-measure the README's findings on the laws"),
    "survey": ("harness.survey.cli", "departure distributions over families of impacts"),
    "experiments": ("harness.experiments.cli",
                    "the laws against measured impacts (Fazeli 2017 drops, Kharaz 2001)"),
    "calibrate": ("harness.experiments.calibrate_cli",
                  "fit an engine's own knobs to the drops or to a law by a small grid"),
    "cache": ("harness.store.cli", "the result cache: info (where, how big), prune, clear"),
    "engines": ("harness.engines.listing",
                "the engines: installed or why not, presets, settings with units and bounds"),
}

#: What exit status 1 means, for the commands that return it (every other command returns
#: 0, 2 or 3 only; compare and export write their own).
EXIT_ONE = {
    "suite": "done, but a gate or an unexplained miss of Table 3 failed",
    "run": "done, but a gate of a scenario ([expect.gate]) failed",
    "paper": "done, but a printed cell of Table 3 is neither reproduced nor explained",
    "bench": "done, but a self-check failed (an engine not bit-identical on a rerun, or "
             "accurate off newton-lcp)",
    "stress": "done, but a stress check failed",
    "findings": "--check: a number the README or docs state differs from what its command "
                "gives",
    "new": "the file exists (use --force to overwrite it)",
}
#: The commands that write results even when an engine run ended in an error (status 4).
EXIT_FOUR = ("run", "suite", "survey")


def exit_status_help(command: str | None) -> str:
    """The exit statuses ``command`` can return (all of them for the top-level help)."""
    lines = ["exit status:", "  0 done, every check passed"]
    if command is None:
        lines += ["  1 done, but a check failed: a gate for run and suite; paper, bench, stress",
                  "    and findings --check their own (see each command's help)"]
    elif command in EXIT_ONE:
        lines.append(f"  1 {EXIT_ONE[command]}")
    lines += ["  2 bad input: an option, a scenario file or a results file (one line each)",
              "  3 internal error: a bug in the harness (IMPACT_HARNESS_TRACEBACK=1 shows it)"]
    if command == "survey":
        lines += ["  4 done, tables written, but an engine run raised (each an ENGINE ERROR "
                  "line, its", "    run recorded error with why); or chunks were stopped by "
                  "--task-time-limit:", "    the finished chunks kept, no tables (the same "
                  "command runs the others)"]
    elif command is None or command in EXIT_FOUR:
        lines += ["  4 run, suite and survey: done, but an engine run ended in an error (an",
                  "    exception of the engine, or its --task-time-limit): its record says "
                  "which"]
    return "\n".join(lines)


class OneLineParser(argparse.ArgumentParser):
    """A parser whose refusal of an option is one line on stderr, exit status 2: the
    command, the option, what was given and what is allowed (its usage is in --help)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: {message} (see --help)\n")


def build_parser(command: str | None) -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog="impact-harness",
        description="Validation harness for planar rigid-body impact with friction.",
        epilog=exit_status_help(None), formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND",
                                       parser_class=OneLineParser)
    for name, (module_name, help_text) in COMMANDS.items():
        sub = subparsers.add_parser(name, help=help_text, description=help_text,
                                    epilog=exit_status_help(name),
                                    formatter_class=argparse.RawDescriptionHelpFormatter)
        if name == command:
            module = importlib.import_module(module_name)
            add = getattr(module, f"add_{name}_arguments", None) or module.add_arguments
            add(sub)
            sub.set_defaults(handler=getattr(module, f"main_{name}", None) or module.main)
    return parser


#: The commands whose --out is a file, checked by the command itself (a second export to
#: the same file was refused as "not a directory").
FILE_OUT_COMMANDS = frozenset({"export"})


def out_problem(out) -> str | None:
    """Why ``--out`` (a directory: every command's but :data:`FILE_OUT_COMMANDS`') cannot be
    written into, or None (also
    when it does not exist yet: the command makes it). Checked before any work."""
    if out is None:
        return None
    path = Path(out)
    try:
        if path.exists() and not path.is_dir():
            return "is not a directory (a file or a device); allowed: a directory"
        if path.is_dir() and not os.access(path, os.W_OK | os.X_OK):
            return "cannot write there: permission denied"
    except OSError as error:  # a name too long, a loop of links
        return f"{error.strerror or error}"
    return None


def main(argv: list[str] | None = None) -> int:
    # Nothing the command runs renders: MuJoCo then skips loading its OpenGL context (glfw,
    # a start-up cost every command that loads the engines would pay). A value the user set is kept.
    os.environ.setdefault("MUJOCO_GL", "disable")
    argv = list(sys.argv[1:] if argv is None else argv)
    command = next((arg for arg in argv if not arg.startswith("-")), None)
    parser = build_parser(command if command in COMMANDS else None)
    args = parser.parse_args(argv)  # a bad option: one line, SystemExit(2)
    if getattr(args, "handler", None) is None:
        parser.print_help()
        return 2
    problem = bounds.environment_problem()
    if problem is not None:
        print(f"impact-harness {args.command}: {problem}", file=sys.stderr)
        return 2
    out = None if args.command in FILE_OUT_COMMANDS else getattr(args, "out", None)
    problem = out_problem(out)
    if problem is not None:
        print(f"impact-harness {args.command}: --out {args.out}: {problem}", file=sys.stderr)
        return 2
    try:
        return int(args.handler(args) or 0)
    except KeyboardInterrupt:
        print("impact-harness: interrupted; finished engine runs are in the cache",
              file=sys.stderr)
        return 130
    except OSError as error:
        if isinstance(error, NotRegularFile):  # a link or a device found at an output
            print(f"impact-harness {args.command}: {error} (remove it, or choose another "
                  "output)", file=sys.stderr)
            return 2
        if error.errno not in ENVIRONMENT_ERRORS:
            return _internal_error(args.command, error)
        # the machine, not the harness: a full disk, a read-only one, a quota
        print(f"impact-harness {args.command}: cannot write {error.filename or 'an output'}: "
              f"{error.strerror or error} (finished engine runs are in the cache; free "
              "space or choose another place)", file=sys.stderr)
        return 2
    except Exception as error:  # noqa: BLE001 - any bug: one line, the traceback on request
        return _internal_error(args.command, error)


#: The errors of writing that are the machine's, not a bug (exit status 2, one line).
ENVIRONMENT_ERRORS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EFBIG})


def _internal_error(command: str, error: BaseException) -> int:
    if os.environ.get("IMPACT_HARNESS_TRACEBACK"):
        traceback.print_exception(error)
    print(f"impact-harness {command}: internal error: {type(error).__name__}: {error} "
          "(a bug; set IMPACT_HARNESS_TRACEBACK=1 for the traceback)", file=sys.stderr)
    return 3


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
