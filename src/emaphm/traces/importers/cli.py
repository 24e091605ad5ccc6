"""``emaphm import``: a bench export into an emaphm trace, through a channel map."""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

from ..._cli_common import UsageError, out_path

__all__ = ["register", "cmd_import"]


def _source(name: str) -> Path:
    from ..._files import regular_file

    return regular_file(name, "source", give="the exported file", error=UsageError,
                        missing=UsageError)


def cmd_import(args: argparse.Namespace) -> int:
    from . import Window, describe, import_trace, inspect_source, load_map, starter_map
    from ..container import TraceWarning
    from ..files import write_trace
    from .channel_map import SourceOptions

    source = _source(args.source)
    cmap = load_map(args.map) if args.map else None
    if args.inspect:
        info = inspect_source(source, cmap.source if cmap else SourceOptions())
        if info.damage:
            warnings.warn(TraceWarning(f"{source}: {info.damage}; listed below: what of it can be read"),
                          stacklevel=2)
        # all of it TOML (the table as comments): `--inspect > map.toml` is a map to edit
        print("\n".join(f"# {line}" for line in describe(info).splitlines()))
        print("#")
        print(starter_map(info), end="")
        return 0
    if cmap is None or args.out is None:
        raise UsageError("give --map MAP.toml and --out TRACE.csv|.parquet (or --inspect to list "
                         f"the channels of {source.name} and print a starter map)")
    out = out_path(args.out, (".csv", ".parquet"), "--out", inputs=[source, args.map])
    window = Window.parse(args.window)
    t0 = time.perf_counter()
    trace = import_trace(source, cmap, window=window, map_name=str(args.map))
    write_trace(trace, out, finite=True)
    if not args.quiet:
        derived = trace.meta.get("derived", {})
        extra = "".join(f"; {k} {v}" for k, v in derived.items())
        print(f"wrote {out} ({trace.n:,} samples, {trace.duration:.6g} s at {1 / trace.dt:.6g} Hz, "
              f"from {source.name} in {time.perf_counter() - t0:.2f} s{extra})", file=sys.stderr)
    return 0


def register(sub) -> None:
    p = sub.add_parser("import", help="import a bench export (CSV, Parquet, MATLAB, TDMS, MDF 4)",
                       description="Read a bench export through a channel map (TOML) and write "
                                   "an emaphm trace that diagnose, calibrate and history add "
                                   "accept. See docs/bench-import.md.")
    p.add_argument("source", help="the export: .csv/.txt, .parquet, .mat, .tdms, .mf4")
    p.add_argument("--map", help="channel map, .toml: which channel is which column, its unit")
    p.add_argument("--out", help="the trace to write, .csv or .parquet")
    p.add_argument("--inspect", action="store_true",
                   help="list the channels, units and rates of SOURCE and print a starter map "
                        "(all TOML: `--inspect > map.toml` gives a map to edit)")
    p.add_argument("--window", help="import START:END seconds of the recording's time only "
                                    "(either may be left out), e.g. 1800:1830")
    p.add_argument("--quiet", action="store_true", help="no summary line")
    p.set_defaults(func=cmd_import)
