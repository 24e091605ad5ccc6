"""Reading and writing traces at scale: the limits of issue 25 and the 1-hour bench export
of issue 22.

Run: ``python benchmarks/bench_import.py [--hours 1] [--folder /tmp/x]``
-> ``benchmarks/results/import.md`` and ``import.json`` (the table is printed too).

Every measurement runs in a fresh process, as a user's command would, and reports its
wall time, its CPU time (``getrusage(RUSAGE_CHILDREN)``) and its peak resident memory
(``VmHWM``, read by the process itself at its end), beside the load average:

* the CSV writer: 1,000,000 samples with the vectorized writer (pyarrow) and with the
  previous one (``repr`` of each float, joined in Python), side by side in one process;
* reading a CSV trace at the sample limit (2,000,000 rows) with validation: the peak
  memory per sample (``emaphm.traces.limits.PEAK_BYTES_PER_SAMPLE``);
* refusing a 5,000,000-row CSV (short rows, under the file-size limit, so that it is the
  row count that refuses it, while streaming) and a 5,000,000-row CSV written by emaphm
  (700 MB, refused by its size before it is read); target under 5 s and 500 MB;
* ``emaphm import`` of a 1-hour, 20 kHz export (72,000,000 samples of 7 channels) as a
  CSV (7 GB: it must be parsed through to the window) and as NI TDMS (float64, 4 GB: read
  in slices), a 30 s window at its end; target under a minute on two cores.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import io
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from _machine import machine as _machine  # the scripts run from benchmarks/

ROOT = Path(__file__).resolve().parent
RATE = 20_000.0
CHUNK = 1_000_000


def machine() -> str:
    return _machine("pyarrow")


_PEAK = """
import json, sys, time
t0 = time.perf_counter()
rc = 0
try:
{body}
except SystemExit as exc:
    rc = exc.code
except Exception as exc:  # noqa: BLE001
    rc = type(exc).__name__ + ": " + str(exc)[:300]
wall = time.perf_counter() - t0
hwm = [l for l in open("/proc/self/status") if l.startswith("VmHWM")][0].split()[1]
print(json.dumps({{"rc": rc, "inner_s": wall, "peak_mb": int(hwm) / 1024}}))
"""


def _run(body: str) -> dict:
    """``body`` (indented Python) in a fresh process: wall, CPU, peak RSS, its outcome."""
    code = _PEAK.format(body="\n".join("    " + line for line in body.strip().splitlines()))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    try:
        res = json.loads(out.stdout.strip().splitlines()[-1])
    except (IndexError, json.JSONDecodeError):
        raise RuntimeError(out.stderr[-2000:]) from None
    res.update(wall_s=wall, cpu_s=(after.ru_utime - before.ru_utime)
               + (after.ru_stime - before.ru_stime), load=load0, stderr=out.stderr.strip()[-400:])
    return res


# ----------------------------------------------------------------------------- signals
def _signals(t: np.ndarray, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """A servo moving back and forth (4 rad, 0.5 Hz) with three sinusoidal currents and
    20 mA of noise: what a bench records, continuous over any length."""
    w = 2 * np.pi * 0.5
    theta = 4.0 * np.sin(w * t)
    omega = 4.0 * w * np.cos(w * t)
    elec = 4 * theta
    amp = 2.0 + 0.5 * np.cos(w * t)
    cols = {"t": t, "theta_ref": theta + 0.01 * np.cos(w * t), "theta_m": theta, "omega_m": omega}
    for k, name in enumerate(("i_a", "i_b", "i_c")):
        cols[name] = amp * np.sin(elec - 2 * np.pi * k / 3) + 0.02 * rng.standard_normal(t.size)
    return cols


def _write_hour_csv(path: Path, n: int) -> float:
    import pyarrow as pa
    import pyarrow.csv as pcsv

    t0 = time.perf_counter()
    rng = np.random.default_rng(0)
    with open(path, "wb") as fh:
        fh.write(b"# exported by rig 3\nTime [s],Cmd [rad],Pos [rad],Speed [rad/s],IU [A],IV [A],IW [A]\n")
        for a in range(0, n, CHUNK):
            cols = _signals(np.arange(a, min(a + CHUNK, n)) / RATE, rng)
            pcsv.write_csv(pa.table(cols), fh, pcsv.WriteOptions(include_header=False))
    return time.perf_counter() - t0


def _write_hour_tdms(path: Path, n: int) -> float:
    from nptdms import ChannelObject, TdmsWriter

    t0 = time.perf_counter()
    rng = np.random.default_rng(0)
    names = {"theta_ref": "Cmd", "theta_m": "Pos", "omega_m": "Speed", "i_a": "IU",
             "i_b": "IV", "i_c": "IW"}
    units = {"theta_ref": "rad", "theta_m": "rad", "omega_m": "rad/s", "i_a": "A", "i_b": "A",
             "i_c": "A"}
    with TdmsWriter(path) as w:
        for a in range(0, n, CHUNK):
            cols = _signals(np.arange(a, min(a + CHUNK, n)) / RATE, rng)
            w.write_segment([ChannelObject("Rig", names[k], cols[k], properties={
                "unit_string": units[k], "wf_increment": 1 / RATE, "wf_start_offset": 0.0})
                for k in names])
    return time.perf_counter() - t0


_CSV_MAP = """[channels]
t = { name = "Time" }
theta_ref = { name = "Cmd" }
theta_m = { name = "Pos" }
omega_m = { name = "Speed" }
i_a = { name = "IU" }
i_b = { name = "IV" }
i_c = { name = "IW" }
"""
#: the TDMS export has no time channel: its waveforms carry their rate
_TDMS_MAP = '[source]\ngroup = "Rig"\n' + _CSV_MAP.replace('t = { name = "Time" }\n', "")


# ----------------------------------------------------------------------------- parts
def writer_speed(folder: Path) -> dict:
    body = f"""
import numpy as np, time, io
from emaphm.traces import Trace, write_trace
from emaphm.traces.csv_format import _csv_chunks
n = 1_000_000
rng = np.random.default_rng(0)
tr = Trace(t=np.arange(n) / 2e4, theta_ref=rng.random(n), theta_m=rng.random(n),
           omega_m=rng.random(n), i_abc=rng.standard_normal((n, 3)), torque=rng.random(n))
c0 = time.process_time(); write_trace(tr, {str(folder / 'w.csv')!r}); new = time.process_time() - c0
size = __import__('os').path.getsize({str(folder / 'w.csv')!r})
data = np.column_stack(list(tr.columns().values()))
c0 = time.process_time()
buf = io.StringIO()
for a in range(0, n, 8192):
    buf.write("".join(",".join(map(repr, row)) + "\\n" for row in data[a:a + 8192].tolist()))
old = time.process_time() - c0
print(__import__('json').dumps({{"new_cpu_s": new, "old_cpu_s": old, "mb": size / 1e6}}))
"""
    out = subprocess.run([sys.executable, "-c", body], capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def read_at_limit(folder: Path) -> dict:
    from emaphm.traces import Trace, write_trace

    n = 2_000_000
    rng = np.random.default_rng(1)
    cols = _signals(np.arange(n) / RATE, rng)
    tr = Trace(t=cols["t"], theta_ref=cols["theta_ref"], theta_m=cols["theta_m"],
               omega_m=cols["omega_m"], i_abc=np.column_stack([cols["i_a"], cols["i_b"], cols["i_c"]]))
    path = write_trace(tr, folder / "limit.csv")
    res = _run(f"""
from emaphm.traces import read_trace
tr = read_trace({str(path)!r})
assert tr.n == {n}
""")
    res.update(samples=n, mb=path.stat().st_size / 1e6)
    return res


def refusals(folder: Path) -> dict:
    short = folder / "short_rows.csv"
    with open(short, "wb") as fh:
        fh.write(b"t,theta_ref,theta_m,omega_m,i_a,i_b,i_c\n")
        for _ in range(5):
            fh.write(b"0,0,0,0,0,0,0\n" * 1_000_000)
    from emaphm.traces import Trace, write_trace

    n = 5_000_000
    rng = np.random.default_rng(2)
    cols = _signals(np.arange(n) / RATE, rng)
    big = write_trace(Trace(t=cols["t"], theta_ref=cols["theta_ref"], theta_m=cols["theta_m"],
                            omega_m=cols["omega_m"],
                            i_abc=np.column_stack([cols["i_a"], cols["i_b"], cols["i_c"]])),
                      folder / "five_million.csv")
    del cols
    out = {}
    for name, path in (("rows", short), ("size", big)):
        res = _run(f"""
from emaphm.cli import main
sys.exit(main(["diagnose", {str(path)!r}]))
""")
        res["mb"] = path.stat().st_size / 1e6
        out[name] = res
        path.unlink()
    return out


def hour_import(folder: Path, hours: float) -> dict:
    n = int(hours * 3600 * RATE)
    end = n / RATE
    out = {"samples": n}
    for fmt, writer, text in (("csv", _write_hour_csv, _CSV_MAP),
                              ("tdms", _write_hour_tdms, _TDMS_MAP)):
        src = folder / f"hour.{fmt}"
        write_s = writer(src, n)
        (folder / f"{fmt}.toml").write_text(text)
        res = _run(f"""
from emaphm.cli import main
rc = main(["import", {str(src)!r}, "--map", {str(folder / f'{fmt}.toml')!r}, "--out",
           {str(folder / f'hour_{fmt}.parquet')!r}, "--window", "{end - 30:g}:{end:g}"])
assert rc == 0, rc
""")
        from emaphm.traces import read_trace

        got = read_trace(folder / f"hour_{fmt}.parquet")
        res.update(write_s=write_s, gb=src.stat().st_size / 1e9, kept=got.n)
        out[fmt] = res
        src.unlink()
    return out


# ----------------------------------------------------------------------------- report
def report(r: dict) -> str:
    w, lim, ref, hr = r["writer"], r["limit"], r["refusals"], r["hour"]
    ratio = w["old_cpu_s"] / w["new_cpu_s"]
    lines = [
        "## Trace files at scale: limits, the CSV writer, a 1-hour bench export",
        "",
        f"`python benchmarks/bench_import.py` on {r['machine']}, {r['date']} (load average "
        f"{r['load']:.1f} at the start; a shared machine). Each row is a fresh process; CPU time "
        "is its user + system time (pyarrow's threads included), peak is its resident high-water "
        "mark (VmHWM).",
        "",
        "| what | wall s | CPU s | peak MB | result |",
        "|---|---|---|---|---|",
        f"| read + validate a 2,000,000-row CSV trace (the sample limit, {lim['mb']:.0f} MB) | "
        f"{lim['wall_s']:.2f} | {lim['cpu_s']:.2f} | {lim['peak_mb']:.0f} | "
        f"{lim['peak_mb'] * 1e6 / lim['samples']:.0f} bytes per sample at the peak (the trace "
        "holds 56) |",
    ]
    for key, what in (("rows", "refuse a 5,000,000-row CSV of short rows ({mb:.0f} MB: refused "
                                "while streaming, at the row limit)"),
                      ("size", "refuse a 5,000,000-row CSV written by emaphm ({mb:.0f} MB: "
                               "refused by its size, unread)")):
        x = ref[key]
        lines.append(f"| {what.format(mb=x['mb'])} | {x['wall_s']:.2f} | {x['cpu_s']:.2f} | "
                     f"{x['peak_mb']:.0f} | exit {x['rc']}, one line |")
    for fmt, what in (("csv", "CSV, 7 channels with the time"),
                      ("tdms", "NI TDMS, 6 float64 waveforms")):
        x = hr[fmt]
        lines.append(
            f"| `emaphm import` of a {r['hours']:g}-hour 20 kHz {what} ({hr['samples']:,} "
            f"samples, {x['gb']:.1f} GB), the last 30 s | {x['wall_s']:.1f} | "
            f"{x['cpu_s']:.1f} | {x['peak_mb']:.0f} | {x['kept']:,} samples kept "
            f"(file written in {x['write_s']:.0f} s) |")
    lines += [
        "",
        f"The CSV writer, 1,000,000 samples x 8 columns ({w['mb']:.0f} MB), CPU time side by side "
        f"in one process: {w['new_cpu_s']:.2f} s vectorized (pyarrow, "
        f"{1 / w['new_cpu_s']:.2f} M rows/s) against {w['old_cpu_s']:.2f} s for the previous "
        f"`repr`-per-float writer: {ratio:.1f}x faster.",
        "",
        "Targets (issue 25 and 22): the refusal of a 5,000,000-row CSV under 5 s and 500 MB; the "
        "1-hour import in bounded memory (the peak above is the window kept and one block, "
        "whatever the length of the export) and under a minute on two cores.",
    ]
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--hours", type=float, default=1.0)
    ap.add_argument("--report-only", action="store_true",
                    help="write import.md again from import.json (no measurement)")
    ap.add_argument("--folder", default=None, help="scratch folder (default: a temporary one)")
    args = ap.parse_args()
    if args.report_only:
        (ROOT / "results" / "import.md").write_text(
            report(json.loads((ROOT / "results" / "import.json").read_text())))
        return
    folder = Path(args.folder or tempfile.mkdtemp(prefix="emaphm-bench-import-"))
    folder.mkdir(parents=True, exist_ok=True)
    r = {"machine": machine(), "date": _dt.datetime.now(_dt.timezone.utc).strftime(
        "%Y-%m-%d %H:%M UTC"), "load": os.getloadavg()[0], "hours": args.hours}
    try:
        r["writer"] = writer_speed(folder)
        print("writer", r["writer"], flush=True)
        r["limit"] = read_at_limit(folder)
        print("limit", r["limit"], flush=True)
        r["refusals"] = refusals(folder)
        print("refusals", r["refusals"], flush=True)
        r["hour"] = hour_import(folder, args.hours)
        print("hour", r["hour"], flush=True)
    finally:
        if args.folder is None:
            shutil.rmtree(folder, ignore_errors=True)
    (ROOT / "results" / "import.json").write_text(json.dumps(r, indent=1))
    text = report(r)
    (ROOT / "results" / "import.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
