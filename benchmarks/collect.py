"""Assemble BENCHMARKS.md from the sections the benchmark scripts write.

Each script in ``benchmarks/`` writes its own measured section under
``benchmarks/results/*.md`` (with its machine and date); this only
concatenates them, in a fixed order, under a short header.

Run: ``python benchmarks/collect.py``.
"""

from pathlib import Path

ROOT = Path(__file__).parent
ORDER = ["plant.md", "commissioning.md", "assess.md", "pipeline.md", "identification.md", "identification_twin.md",
         "false_alarms.md", "models.md", "batches.md", "model_report.md", "optim.md", "prognosis.md",
         "demagnetization.md", "demagnetization-ema-270v-750w.md", "resistance.md", "sensor_drift.md",
         "inspection.md", "fault_coverage.md", "fleet.md", "long_history.md", "versions.md",
         "import.md", "batch_identify.md", "drives-all.md",
         "drive_cost.md"]
#: written by benchmarks/run_paper_campaign.py beside the campaign report
CAMPAIGN = ROOT.parent / "docs" / "results" / "timing.md"
HEADER = """# Benchmarks

Measured numbers only: each section below is written by the script named in it, on the
machine and at the date it states. Re-run a script and then `python benchmarks/collect.py`
to refresh this file. Timings are taken on one core per process unless said otherwise;
the machines are shared, so compare ratios measured side by side in one run.

Accuracy is judged on **plant traces** first: the reference model is a plant with physics
the monitoring model lacks (the Stribeck drop, the backlash contact resolved at 1 us with
the unit's own stiffness, leakage and fault loops resolved with the PWM ripple) and, where
stated, production units within tolerances. *Twin* traces (the monitoring model's own
currents with the same sensor noise) are the inverse crime, shown beside for comparison.
The monitoring model closes the backlash on a compliant contact since version 0.3
(2026-11-23 17:00 UTC), and its kernels carry a per-candidate load column (the mismatch
check's unreported load) since 2026-11-23 18:50 UTC, at 0.99x the kernel time side by side
(*The load column's cost* below); sections dated before 17:00 were measured with the
earlier rigid contact. The optimizer section runs the optimizers on standard test
functions: it does not depend on the actuator model. Every script re-runs its section.

| section | script |
|---|---|
| FDI on plant traces beside twin traces (physical faults, thresholds, verdicts) | `benchmarks/bench_plant.py` |
| commissioning production units (`emaphm calibrate`) | `benchmarks/bench_commissioning.py` |
| what the method detects on an actuator, and how often it false-alarms (`emaphm assess`) | `benchmarks/bench_assess.py` |
| faults beyond the paper: severe shorts, demagnetization, current sensors | `benchmarks/bench_fault_coverage.py` |
| the default pipeline (`lsq`) beside SciPy's DE and PSO, twin and plant | `benchmarks/bench_identification.py --pipeline` |
| monitoring/reference model speed | `benchmarks/bench_models.py` |
| small populations (least-squares batches) against N = 50 | `benchmarks/bench_models.py --small-batches-only` |
| model agreement and sensitivity | `benchmarks/model_report.py` |
| identification accuracy and speed (paper Table 3 layout), plant and twin | `benchmarks/bench_identification.py [--model monitoring]` |
| false alarms and fault naming | `benchmarks/bench_false_alarms.py` |
| optimizers vs scipy and library baselines | `benchmarks/bench_optim.py` |
| the paper's full campaign | `benchmarks/run_paper_campaign.py` |
| prognosis: RUL coverage and error | `benchmarks/bench_prognosis.py` (figures in `docs/prognosis.md`) |
| demagnetization trended on plant traces: RUL coverage, plans, the flux read | `benchmarks/bench_demagnetization.py` (both actuators) |
| a high-resistance connection: POD and false alarms, both paths, both actuators | `emaphm assess --grids resistance [--drive-signals]` (commands in the section) |
| the current sensors' indicators against the plant's sensors (model discrepancy) | `benchmarks/bench_sensor_drift.py` |
| inspection planning: risk calibration, the risk policy against fixed intervals | `benchmarks/bench_inspection.py` (method in `docs/inspection-planning.md`) |
| fleet health site: build time | `benchmarks/bench_fleet.py` |
| prognosis of one actuator as its history grows (time, memory) | `benchmarks/bench_long_history.py` |
| two versions side by side (a refactor keeps the speed) | `benchmarks/bench_versions.py` |
| trace files at scale: the limits' refusals, the CSV writer, a 1-hour bench export (`emaphm import`) | `benchmarks/bench_import.py` |
| a batch of traces on worker processes against the calls in a row | `benchmarks/bench_batch.py` |
| drives that are not emaphm's: recorded voltages (A), the drive described (B), neither (C), recorded current references (D) | `benchmarks/bench_drives.py` |
| the cost of identifying from what the drive recorded, beside 216ed3d's modelled controller | `benchmarks/bench_drive_cost.py` |

"""


def main() -> None:
    parts = [HEADER]
    results = ROOT / "results"
    names = [n for n in ORDER if (results / n).exists()]
    names += sorted(p.name for p in results.glob("*.md") if p.name not in ORDER)
    for name in names:
        parts.append((results / name).read_text().strip() + "\n")
        if name == "false_alarms.md" and CAMPAIGN.exists():
            parts.append(CAMPAIGN.read_text().strip() + "\n\nTables and figures: "
                         "[docs/results/report.md](docs/results/report.md).\n")
    (ROOT.parent / "BENCHMARKS.md").write_text("\n".join(parts))


if __name__ == "__main__":
    main()
