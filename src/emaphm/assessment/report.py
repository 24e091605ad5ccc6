"""The assessment as data (:func:`summarize` -> the dict of ``assessment.json``, the
contract of ``docs/assessment.md``) and as a report (:func:`write_outputs`: the JSON,
``report.md`` and the POD figures). Figures and tables read that dict only.
"""

from __future__ import annotations

import json
import math
from collections import Counter
from pathlib import Path
from typing import Any, Mapping, Sequence

from .spec import HEALTHY, AssessmentSpec, _grid
from .stats import pod_fit, proportion

__all__ = ["summarize", "write_outputs", "conclusions", "SCHEMA", "PCI_TARGET"]

#: The schema of ``assessment.json`` (its ``schema_version``).
SCHEMA = 1
#: ``min_detectable``: the smallest severity whose probability of correct identification
#: has its 95 % lower bound at or above this.
PCI_TARGET = 0.9


def _runs(assessed: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Every diagnosis of the reported units, flat, each with its unit."""
    out = []
    for u in assessed:
        for r in u.get("runs", ()):
            out.append({"unit": u["index"], "unit_seed": u["unit_seed"], **r})
    return out


def _false_alarm(runs: list[dict], path: str) -> dict[str, Any]:
    rs = [r for r in runs if r["case"] == HEALTHY and r["path"] == path]
    v = Counter(r["verdict"] for r in rs)
    p = proportion(v["faulty"], len(rs))
    units = {r["unit"] for r in rs}
    return {"n": len(rs), "faulty": v["faulty"], "unexplained": v["unexplained"],
            "healthy": v["healthy"], "refused": v["refused"], "rate": p.rate, "lo": p.lo,
            "hi": p.hi,
            "interval": "wilson", "units": len(units),
            "units_with_false_alarm": len({r["unit"] for r in rs if r["verdict"] == "faulty"}),
            "named": dict(Counter(f[0] for r in rs if r["verdict"] == "faulty"
                                  for f in r["named"]))}


def _pod(spec: AssessmentSpec, runs: list[dict]) -> tuple[dict, dict, dict]:
    """Rows per grid and severity, ``min_detectable`` and the POD fits."""
    pod, least, fits = {}, {}, {}
    for name in spec.grids or ():
        _, g = _grid(name)
        rs = [r for r in runs if r["case"] == name and r["path"] == "calibrated"]
        rows = []
        for s in spec.severities_of(name):
            at = [r for r in rs if math.isclose(r["severity"], s)]
            n = len(at)
            det = sum(r["verdict"] == "faulty" for r in at)
            right = sum(bool(r["right"]) for r in at)
            p = proportion(right, n)
            rows.append({"severity": s, "severity_unit": g.severity_unit,
                         "magnitude": g.magnitude(s), "n": n, "detected": det, "right": right,
                         "unexplained": sum(r["verdict"] == "unexplained" for r in at),
                         "refused": sum(r["verdict"] == "refused" for r in at),
                         "pod": det / n if n else None, "pci": p.rate if n else None,
                         "lo": p.lo, "hi": p.hi})
        pod[name] = rows
        ok = [r for r in sorted(rows, key=lambda r: r["magnitude"])
              if r["n"] and r["lo"] >= PCI_TARGET]
        least[name] = ok[0]["severity"] if ok else None
        fits[name] = pod_fit([r["magnitude"] for r in rs], [bool(r["right"]) for r in rs]).to_dict()
    return pod, least, fits


def _confusion(spec: AssessmentSpec, runs: list[dict]) -> dict[str, dict[str, int]]:
    """True case (healthy, each grid) -> what the calibrated diagnosis said: ``healthy``,
    ``unexplained``, ``refused`` (the trace itself), the one mode it named (``mode`` or
    ``mode (wrong phase)``), or ``several``."""
    out: dict[str, dict[str, int]] = {}
    for case in (HEALTHY, *(spec.grids or ())):
        c: Counter = Counter()
        for r in runs:
            if r["case"] != case or r["path"] != "calibrated":
                continue
            if r["verdict"] != "faulty":
                c[r["verdict"]] += 1
            elif len(r["named"]) > 1:
                c["several"] += 1
            else:
                mode, phase = r["named"][0]
                wrong = r["phase"] is not None and mode == r["mode"] and phase != r["phase"]
                c[f"{mode} (wrong phase)" if wrong else mode] += 1
        out[case] = dict(sorted(c.items()))
    return out


def summarize(spec: AssessmentSpec, tuned: Mapping[str, Any] | None,
              thresholds: Mapping[str, float], tune_results: Sequence[Mapping[str, Any]],
              assessed: Sequence[Mapping[str, Any]], *, wall_s: float,
              version: str, tracking: Mapping[str, float]) -> dict[str, Any]:
    """The assessment as the data of ``assessment.json`` (see ``docs/assessment.md``)."""
    runs = _runs(assessed)
    pod, least, fits = _pod(spec, runs)
    failures = [u for u in (*tune_results, *assessed) if "error" in u]
    refused = [u for u in (*tune_results, *assessed) if "calibration_error" in u]
    units = (*tune_results, *assessed)
    cpu = {"tune": sum(u.get("cpu_s", 0.0) for u in tune_results),
           "assess": sum(u.get("cpu_s", 0.0) for u in assessed),
           "calibrate": sum(u.get("calibrate_cpu_s", 0.0) for u in units),
           "diagnose": sum(r.get("cpu_s", 0.0) for u in units
                           for r in (*u.get("runs", ()), *u.get("healthy", ()),
                                     *u.get("crosstalk", ())))}
    return {
        "schema_version": SCHEMA, "emaphm_version": version,
        "actuator": spec.params.get("name"), "spec": spec.to_dict(),
        "tracking": dict(tracking),
        "false_alarm": {"datasheet": _false_alarm(runs, "datasheet"),
                        "calibrated": _false_alarm(runs, "calibrated")},
        "pod": pod, "min_detectable": least, "pod_fit": fits,
        "confusion": _confusion(spec, runs),
        "thresholds": {"values": dict(thresholds), "tuned": spec.tune,
                       "target_far": spec.target_far,
                       "tuning": {k: v.to_dict() for k, v in (tuned or {}).items()}},
        "seeds": {"seed": spec.seed,
                  "tune_unit_seeds": [u["unit_seed"] for u in tune_results],
                  "unit_seeds": [u["unit_seed"] for u in assessed]},
        "calibration_refused": [{"key": u["key"], "unit_seed": u["unit_seed"],
                                 "reason": u["calibration_error"]} for u in refused],
        "failures": [{"key": u["key"], "unit_seed": u["unit_seed"], "error": u["error"]}
                     for u in failures],
        "cpu_s": {**cpu, "total": cpu["tune"] + cpu["assess"],
                  "simulate_and_rest": cpu["tune"] + cpu["assess"] - cpu["calibrate"]
                  - cpu["diagnose"]}, "wall_s": wall_s,
        "runs": runs,
    }


# ----------------------------------------------------------------------------- words

def _pct(x: float) -> str:
    return f"{100 * x:.1f} %" if x < 0.1 else f"{100 * x:.0f} %"


def conclusions(a: Mapping[str, Any]) -> list[str]:
    """Plain-language sentences of the assessment ``a`` (its dict)."""
    name = a.get("actuator") or "this actuator"
    out = []
    cal = a["false_alarm"]["calibrated"]
    if cal["n"]:
        out.append(f"After `emaphm calibrate`, healthy units of {name} are called faulty "
                   f"{cal['faulty']} times in {cal['n']} (95 % interval {_pct(cal['lo'])} to "
                   f"{_pct(cal['hi'])}; {cal['units']} units).")
    sheet = a["false_alarm"]["datasheet"]
    if sheet["n"]:
        out.append(f"On their data sheet, never calibrated, they are called faulty "
                   f"{sheet['faulty']} times in {sheet['n']} (interval {_pct(sheet['lo'])} to "
                   f"{_pct(sheet['hi'])}), and `unexplained` {sheet['unexplained']} times: "
                   "calibrate a unit before trusting a diagnosis of it.")
    small = False
    for grid, rows in a["pod"].items():
        tried = [r for r in rows if r["n"]]
        if not tried:
            continue
        label = grid_label(grid)
        unit = tried[0]["severity_unit"]
        by_size = sorted(tried, key=lambda r: r["magnitude"])
        good = [r for r in by_size if r["pci"] >= PCI_TARGET]
        onwards = [r for i, r in enumerate(by_size)
                   if all(q["pci"] >= PCI_TARGET for q in by_size[i:])]
        if good:
            r = (onwards or good)[0]
            bounded = r["lo"] >= PCI_TARGET     # the interval, not one lucky run, says it
            text = (f"{label}: named right 9 times in 10 or more "
                    + ("" if bounded else "in the runs tried (too few to bound it there) ")
                    + ("from" if onwards else "at") + f" {r['severity']:g} ({unit})"
                    + (" on" if onwards else ", not at every larger severity")
                    + f", {r['right']} times in {r['n']} there (interval {_pct(r['lo'])} to "
                    f"{_pct(r['hi'])})")
        else:
            r = max(tried, key=lambda r: (r["pci"], r["magnitude"]))
            text = (f"{label}: named right at most {r['right']} times in {r['n']} (at "
                    f"{r['severity']:g} {unit}); never 9 times in 10")
        misses = Counter()
        for row in tried:
            misses.update({"unexplained": row["unexplained"], "missed": row["n"] - row["detected"]
                           - row["unexplained"] - row.get("refused", 0),
                           "named with another fault or the wrong one":
                               row["detected"] - row["right"]})
        if any(misses.values()):
            text += "; of its other runs " + ", ".join(f"{v} {k}" for k, v in misses.items() if v)
        least = a["min_detectable"].get(grid)
        if least is not None:
            text += f"; min_detectable {least:g}"
        fit = a["pod_fit"].get(grid, {})
        if fit.get("a90") is not None:
            text += (f"; hit/miss fit a90 = {fit['a90']:.3g}"
                     + (f", a90/95 = {fit['a90_95']:.3g}" if fit.get("a90_95") else "")
                     + " in magnitude")
        out.append(text + ".")
        small = small or tried[0]["n"] < 35
    if small:
        out.append("No severity can show a 95 % lower bound of 0.9 with fewer than 35 runs "
                   "(20 of 20 gives 84 %): min_detectable needs `--units 35` or more.")
    return out


def grid_label(grid: str) -> str:
    """A grid in words: its mode's label, and its variant (``current sensor (offset)``)."""
    from ..modes import MODES

    name, _, variant = grid.partition(":")
    label = MODES[name].label if name in MODES else name.replace("_", " ")
    return (label[0].upper() + label[1:]) + (f" ({variant})" if variant else "")


def _md_table(header: list[str], rows: list[list[Any]]) -> list[str]:
    return (["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
            + ["| " + " | ".join(str(c) for c in row) + " |" for row in rows])


def report_md(a: Mapping[str, Any], figures: Mapping[str, str]) -> str:
    """``report.md`` of the assessment ``a``."""
    spec = a["spec"]
    lines = [f"# Assessment of {a.get('actuator') or 'the actuator'}", "",
             f"emaphm {a['emaphm_version']}; {spec['units']} production units (seed "
             f"{spec['seed']}), thresholds "
             + (f"tuned on {spec['tune_units']} other units for a false-alarm rate under "
                f"{_pct(spec['target_far'])}" if a["thresholds"]["tuned"] else "as given")
             + f"; {a['cpu_s']['total']:.0f} s of CPU, {a['wall_s']:.0f} s wall. Diagnosed "
             + ("from the drive's recorded voltage commands (the controller not modelled)"
                if spec.get("drive_signals") else "with the modelled controller")
             + ".", "",
             "## Conclusions", "", *[f"- {c}" for c in conclusions(a)], "",
             "## False alarms (healthy units)", ""]
    rows = []
    for path, fa in a["false_alarm"].items():
        if fa["n"]:
            rows.append([path, fa["n"], fa["units"], fa["faulty"], fa["unexplained"],
                         fa["healthy"], f"{fa['rate']:.3f}", f"{fa['lo']:.3f}-{fa['hi']:.3f}"])
    lines += _md_table(["parameters", "traces", "units", "faulty", "unexplained", "healthy",
                        "rate", "95 % (Wilson)"], rows)
    lines += ["", "## Thresholds", ""]
    tuning = a["thresholds"]["tuning"]
    rows = [[n, f"{v:.4g}", f"{tuning[n]['default']:.4g}" if n in tuning else "",
             _g(tuning[n]["largest"]) if n in tuning else "",
             _g(tuning[n]["crosstalk"]) if n in tuning else "",
             tuning[n]["rule"] if n in tuning else ""]
            for n, v in a["thresholds"]["values"].items()]
    lines += _md_table(["threshold", "value", "default", "largest healthy",
                        "largest under another fault", "set by"], rows)
    lines += ["", "## Probability of detection and of correct identification", "",
              "After calibration. `pod`: any fault named; `pci`: the right mode (and phase) "
              "named alone, with its Wilson 95 % interval.", ""]
    for grid, rows_ in a["pod"].items():
        fit = a["pod_fit"][grid]
        lines += [f"### {grid}", ""]
        if grid in figures:
            lines += [f"![{grid}]({figures[grid]})", ""]
        lines += _md_table(["severity", "unit", "n", "pod", "pci", "95 %"],
                           [[f"{r['severity']:g}", r["severity_unit"], r["n"],
                             "" if r["pod"] is None else f"{r['pod']:.2f}",
                             "" if r["pci"] is None else f"{r['pci']:.2f}",
                             f"{r['lo']:.2f}-{r['hi']:.2f}"] for r in rows_])
        least = a["min_detectable"][grid]
        lines += ["", f"min_detectable: {least if least is not None else 'none'}; "
                  + (f"hit/miss fit a90 = {fit['a90']:.3g}" if fit["a90"] else "no hit/miss fit")
                  + (f", a90/95 = {fit['a90_95']:.3g}" if fit["a90_95"] else "")
                  + " (magnitude)" + (f": {fit['note']}" if fit["note"] else ""), ""]
    lines += ["## Confusion (true case -> what was named, calibrated)", ""]
    cols = sorted({c for row in a["confusion"].values() for c in row})
    lines += _md_table(["true case", *cols],
                       [[case, *[row.get(c, 0) for c in cols]]
                        for case, row in a["confusion"].items()])
    if a["calibration_refused"] or a["failures"]:
        lines += ["", "## Units left out", ""]
        lines += [f"- {u['key']} (unit seed {u['unit_seed']}): calibration refused: {u['reason']}"
                  for u in a["calibration_refused"]]
        lines += [f"- {u['key']} (unit seed {u['unit_seed']}): failed: "
                  f"{u['error'].splitlines()[-1]}" for u in a["failures"]]
    return "\n".join(lines) + "\n"


def pod_figure(rows: Sequence[Mapping[str, Any]], fit: Mapping[str, Any], title: str) -> Any:
    """The POD and PCI of one grid against severity, Wilson intervals drawn; the hit/miss
    curve where it was fitted."""
    import numpy as np
    from matplotlib.figure import Figure

    from .stats import PODFit

    fig = Figure(figsize=(5.5, 3.6), layout="constrained")
    ax = fig.add_subplot()
    rs = [r for r in rows if r["n"]]
    s = np.array([r["severity"] for r in rs])
    pci = np.array([r["pci"] for r in rs])
    err = np.array([[r["pci"] - r["lo"] for r in rs], [r["hi"] - r["pci"] for r in rs]])
    ax.errorbar(s, pci, yerr=err, fmt="o", capsize=3, label="right mode named alone (95 %)")
    ax.plot(s, [r["pod"] for r in rs], "s", mfc="none", label="any fault named")
    if fit.get("b0") is not None and rs:
        f = PODFit.from_dict(fit)
        mags = np.array([r["magnitude"] for r in rs])
        order = np.argsort(mags)
        grid = np.linspace(mags.min(), mags.max(), 100)
        # draw against severity: interpolate severity over magnitude along the grid
        ax.plot(np.interp(grid, mags[order], s[order]), f.pod(grid), "-", lw=1,
                label="hit/miss fit (logistic in log size)")
    ax.axhline(PCI_TARGET, color="0.6", lw=0.8, ls="--")
    ax.set_ylim(-0.03, 1.05)
    ax.set_xlabel(rs[0]["severity_unit"] if rs else "severity")
    ax.set_ylabel("probability")
    ax.set_title(title)
    ax.legend(fontsize=7, loc="lower right")
    return fig


def _g(x: Any) -> str:
    """A number in 3 significant digits; a dash where there is none (None, NaN)."""
    return "\u2013" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x:.3g}"


def _finite(obj: Any) -> Any:
    """``obj`` with every float that is not finite as None: JSON has no NaN (a threshold no
    other fault moved has no crosstalk), and a file that holds one is no JSON to a reader
    that keeps to the standard."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, Mapping):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    return obj


def write_outputs(a: Mapping[str, Any], folder: Path) -> list[Path]:
    """Write ``assessment.json``, ``report.md`` and the figures of ``a`` into ``folder``."""
    paths = []
    figures = {}
    for grid, rows in a["pod"].items():
        if not any(r["n"] for r in rows):
            continue
        name = f"pod_{grid.replace(':', '_')}.png"
        pod_figure(rows, a["pod_fit"][grid], grid).savefig(folder / name, dpi=110)
        figures[grid] = name
        paths.append(folder / name)
    (folder / "assessment.json").write_text(
        json.dumps(_finite(a), indent=1, sort_keys=False, allow_nan=False) + "\n")
    (folder / "report.md").write_text(report_md(a, figures))
    return [folder / "assessment.json", folder / "report.md", *paths]

