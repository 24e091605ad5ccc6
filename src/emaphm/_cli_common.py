"""What every ``emaphm`` subcommand shares: the usage error, option types, output paths.

It sits below every subcommand module: :mod:`emaphm.cli`, :mod:`emaphm.campaign.cli` and
:mod:`emaphm.prognosis.cli` import from here, and nothing imports :mod:`emaphm.cli` but
the ``emaphm`` entry point. Importing it is cheap (no NumPy, no model).
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from pathlib import Path
from typing import Any, Callable, Sequence

from ._text import one_line, shown, utf8_text

__all__ = ["EXIT_USAGE", "UsageError", "Parser", "arg_type", "seed", "bounded_int",
           "budget_option", "out_path", "plot_path", "writable_folder", "actuator_id", "MAX_ID_CHARS",
           "negative_values", "shown"]

EXIT_USAGE = 2

#: Longest actuator id the command line takes (the store's own grammar is stricter);
#: anything longer is refused before it is echoed or looked up.
MAX_ID_CHARS = 200

PLOT_SUFFIXES = (".png", ".svg", ".pdf")


class UsageError(Exception):
    """Bad input found after parsing; printed without a traceback, exit status 2."""


class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line (``PROG: error: WHAT; see PROG
    --help``), exit status 2, like every other usage error of emaphm."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(EXIT_USAGE, f"{self.prog}: error: {one_line(message, 500)}; see "
                              f"{self.prog} --help\n")


def arg_type(convert: Callable[[str], Any], valid: Callable[[Any], bool],
             expected: str) -> Callable[[str], Any]:
    """An argparse ``type=``: ``convert`` the text, keep it if ``valid``, else an error
    "``expected``, got 'text'" (exit status 2). Shared by every subcommand."""
    def parse(value: str) -> Any:
        try:
            x = convert(value)
        except (ValueError, OverflowError):
            raise argparse.ArgumentTypeError(f"{expected}, got {shown(value)}") from None
        if not valid(x):
            raise argparse.ArgumentTypeError(f"{expected}, got {shown(value)}")
        return x
    parse.__name__ = convert.__name__          # argparse names the type in its messages
    return parse


seed = arg_type(int, lambda s: s >= 0, "seed must be a non-negative integer")


def bounded_int(lo: int, hi: int, what: str) -> Callable[[str], int]:
    """An argparse ``type=`` for an integer in ``[lo, hi]``; ``what`` says why the bound."""
    return arg_type(int, lambda n: lo <= n <= hi, f"expected an integer from {lo} to {hi} ({what})")


def budget_option(text: str | None) -> Any:
    """The value of a ``--budget`` option: ``"5000"`` -> 5000 evaluations, ``"30s"`` a
    wall-clock budget, None the algorithm's default; checked by
    :func:`emaphm.identify.parse_budget` (a :class:`UsageError` naming the option)."""
    if text is None:
        return None
    if text.strip().startswith("-"):
        raise UsageError(f"--budget: budget must be positive, got {shown(text)}; give evaluations "
                         "(e.g. 5000) or seconds (e.g. 30s)")
    from .identify import parse_budget

    value: Any = int(text) if text.strip().isdigit() else text
    try:
        parse_budget(value)
    except ValueError as exc:
        raise UsageError(f"--budget: {exc}") from None
    return value


def out_path(path: str, suffixes: tuple[str, ...], what: str,
             inputs: Sequence[Any] = ()) -> Path:
    """An output file named by an option: its suffix one of ``suffixes``, its folder there,
    not the path itself a folder and not one of the command's ``inputs`` (paths; None is
    skipped): writing it would destroy what the command reads (else :class:`UsageError`)."""
    p = Path(path)
    for source in inputs:
        if source is not None and _same_file(p, Path(source)):
            raise UsageError(f"{what} {shown(p.name)} is the command's input (the same file): "
                             "writing it would overwrite what is read; give another file name")
    if p.suffix.lower() not in suffixes:
        raise UsageError(f"{what} {shown(path)} must end in {' or '.join(suffixes)}")
    if p.is_dir():
        raise UsageError(f"{what} {path} is a folder; give a file name ending in "
                         f"{' or '.join(suffixes)}")
    if not p.parent.exists():
        raise UsageError(f"{what} {shown(path)}: folder {p.parent} does not exist; create it first")
    writable_folder(p.parent, what)
    return p


def _same_file(a: Path, b: Path) -> bool:
    """Whether ``a`` and ``b`` name one file (links followed); False when either is not there."""
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def writable_folder(folder: Path, what: str) -> Path:
    """``folder`` if it is a folder this process can create files in (tried with an
    anonymous temporary file, which leaves nothing behind), else a :class:`UsageError`:
    an output that cannot be written is refused before any work, not after."""
    import tempfile

    if not folder.is_dir():
        raise UsageError(f"{what}: {folder} is a file, not a folder; give a path in a folder")
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        raise UsageError(f"{what}: cannot write in the folder {folder} ({exc.strerror or exc}); "
                         "give a folder you can write to") from None
    return folder


def plot_path(value: str | None, what: str = "--plot") -> Path | None:
    """The figure file of a ``--plot`` option (None when not given)."""
    return out_path(value, PLOT_SUFFIXES, what) if value else None


def actuator_id(text: str) -> str:
    """An argparse ``type=`` for an actuator id: at most :data:`MAX_ID_CHARS` characters,
    refused (exit status 2) before it is echoed whole or looked up."""
    if len(text) > MAX_ID_CHARS:
        raise argparse.ArgumentTypeError(
            f"actuator id {shown(text)} is longer than {MAX_ID_CHARS} characters; give the id "
            "it was registered with, e.g. EMA-0042")
    return utf8_text(text)           # under LC_ALL=C: the characters typed, not surrogates


# a value that starts like a negative number but that argparse takes for an option
_NEGATIVE = re.compile(r"-(\d|\.\d)")


def _value_options(parser: argparse.ArgumentParser) -> set[str]:
    opts: set[str] = set()
    for action in parser._actions:                       # noqa: SLF001 - argparse has no API
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                opts |= _value_options(sub)
        elif action.option_strings and action.nargs is None:
            opts.update(o for o in action.option_strings if o.startswith("--"))
    return opts


def negative_values(parser: argparse.ArgumentParser, argv: Sequence[str]) -> list[str]:
    """``argv`` with ``--opt -1s`` written ``--opt=-1s`` for every option of ``parser`` that
    takes one value: argparse reads a value such as ``-1s`` or ``-1e6`` as an unknown
    option ("expected one argument"); joined, it reaches the option's own check, which
    says what is wrong with it."""
    opts = _value_options(parser)
    out: list[str] = []
    args = list(argv)
    i = 0
    while i < len(args):
        a = args[i]
        if a == "--":
            out.extend(args[i:])
            break
        if a in opts and i + 1 < len(args) and _NEGATIVE.match(args[i + 1]):
            out.append(f"{a}={args[i + 1]}")
            i += 2
            continue
        out.append(a)
        i += 1
    return out


# ----------------------------------------------------------------------------- long runs
#: Seconds per candidate and model step of a population's fitness on one busy core:
#: BENCHMARKS.md measures 26-28 ns for populations of 50-200 and 48 ns for 10; 40 ns
#: keeps a margin for a loaded machine.
SECONDS_PER_CANDIDATE_STEP = 40e-9
#: Seconds per model step of one calibration simulation (a model built for one candidate,
#: the data sheet's deviations applied, then run): 238 runs of a 0.5 s trace (4000 steps)
#: took 6.7 s of CPU on a loaded 2-core Xeon, 7 us per step.
SECONDS_PER_CALIBRATION_STEP = 7e-6
#: Model runs per trace of a calibration, per free parameter and one more: 238 runs for the
#: 13 parameters (18 per parameter) in that measurement.
CALIBRATION_RUNS_PER_PARAMETER = 20
#: The least-squares pipeline's run in population evaluations' worth: a median 0.26 s of CPU
#: on a 4000-step trace (BENCHMARKS.md, the pipeline section) is about 1,600 at
#: SECONDS_PER_CANDIDATE_STEP; three times that covers its further starts.
LSQ_EQUIVALENT_EVALUATIONS = 5000
#: Cost of one of its candidates (batches of 1 to 10) against one in a population.
LSQ_BATCH_COST = 4
#: An identification or calibration estimated to take longer than this is announced.
LONG_RUN_S = 60.0


def _model_steps(duration_s: float, params: Any) -> float:
    return max(float(duration_s), 0.0) / float(params.inverter.T_s)


def expected_evaluations(algorithm: str, budget: Any = None,
                         options: dict[str, Any] | None = None) -> int | None:
    """Evaluations an identification spends at most in its first run (the metaheuristic's
    iteration limit times its population, plus the polish); None under a wall-clock
    budget, which bounds the time itself."""
    from .identify import DEFAULT_ALGORITHM, POLISH_MAX_EVALUATIONS, parse_budget
    from .optim import get_optimizer
    from .optim.base import MaxEvaluations, MaxIterations

    term = parse_budget(budget)
    if algorithm == DEFAULT_ALGORITHM:
        # the least-squares pipeline evaluates small batches, each candidate costing about
        # LSQ_BATCH_COST times a population's; its whole run, further starts included
        evals = [t.n for t in list(getattr(term, "terms", None) or [term])
                 if isinstance(t, MaxEvaluations)]
        return int(min([LSQ_EQUIVALENT_EVALUATIONS] + [LSQ_BATCH_COST * n for n in evals]))
    try:
        opt = get_optimizer(algorithm, **(options or {}))
    except ValueError:                    # a registered function or solver: no estimate
        return None
    if term is None:
        term = opt.default_termination()
    terms = list(getattr(term, "terms", None) or [term])
    evals = [t.n for t in terms if isinstance(t, MaxEvaluations)]
    if evals:
        return int(min(evals))
    iters = [t.n for t in terms if isinstance(t, MaxIterations)]
    if not iters:
        return None
    pop = int(getattr(opt, "pop_size", None) or 10)
    return int(min(iters)) * pop + pop + POLISH_MAX_EVALUATIONS


def identification_seconds(duration_s: float, params: Any, algorithm: str, budget: Any = None,
                           options: dict[str, Any] | None = None, runs: int = 1) -> float | None:
    """Rough seconds of ``runs`` identifications of a trace lasting ``duration_s``: model
    steps x evaluations x :data:`SECONDS_PER_CANDIDATE_STEP` (None under a wall-clock
    budget)."""
    evals = expected_evaluations(algorithm, budget, options)
    if evals is None:
        return None
    return _model_steps(duration_s, params) * evals * runs * SECONDS_PER_CANDIDATE_STEP


def calibration_seconds(durations_s: Sequence[float], params: Any) -> float:
    """Rough seconds of a calibration on traces lasting ``durations_s``: every trace
    simulated about :data:`CALIBRATION_RUNS_PER_PARAMETER` times per free parameter (and
    once more) by :func:`emaphm.calibration.calibrate`'s least squares."""
    from .calibration import PARAMETERS

    steps = sum(_model_steps(d, params) for d in durations_s)
    runs = CALIBRATION_RUNS_PER_PARAMETER * (len(PARAMETERS) + 1)
    return steps * runs * SECONDS_PER_CALIBRATION_STEP


def warn_if_long(command: str, seconds: float | None, what: str, hint: str,
                 stream: Any = None) -> bool:
    """One line on stderr when ``seconds`` exceeds :data:`LONG_RUN_S`: how long ``what``
    may take and ``hint`` (how to make it shorter). Returns whether it warned."""
    if seconds is None or seconds <= LONG_RUN_S:
        return False
    from .progress import clock

    stream = stream if stream is not None else sys.stderr
    stream.write(f"{command}: note: {what} may take about {clock(seconds)} on one core; {hint}\n")
    stream.flush()
    return True
