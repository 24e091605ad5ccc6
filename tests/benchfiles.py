"""Bench exports of a trace, written with the real libraries as test rigs write them: a
German spreadsheet CSV, MATLAB 5 and 7.3 files with a sample rate and a current probe in
volts, NI TDMS with rpm, ASAM MDF 4 on its own master time base. Each writer returns the
file and the channel map (TOML text) that imports it back."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from emaphm.traces import Trace

#: The current probe of the MATLAB exports: 100 mV per ampere.
PROBE_V_PER_A = 0.1


def german_csv(trace: Trace, path: Path) -> tuple[Path, str]:
    """``;`` between fields, decimal commas, time in ms, positions in degrees, two phase
    currents, a preamble and a units row, Windows-1252 text."""
    lines = ["Pr\u00fcfstand 3; Export der Messung", "Datum: 2026-01-01 08:00",
             "Zeit;Sollposition;Istposition;Strom U;Strom V", "ms;\u00b0;\u00b0;A;A"]
    data = np.column_stack([trace.t * 1e3, np.degrees(trace.theta_ref),
                            np.degrees(trace.theta_m), trace.i_a, trace.i_b])
    lines += [";".join(repr(float(x)).replace(".", ",") for x in row) for row in data]
    path.write_bytes(("\r\n".join(lines) + "\r\n").encode("cp1252"))
    return path, """
[channels]
t = { name = "Zeit", unit = "ms" }
theta_ref = { name = "Sollposition", unit = "deg" }
theta_m = { name = "Istposition" }
i_a = { name = "Strom U" }
i_b = { name = "Strom V", unit = "A" }
[profile]
name = "diagnostic"
"""


def _rate(trace: Trace) -> float:
    return float(round(1.0 / trace.dt, 6))


def matlab_v5(trace: Trace, path: Path) -> tuple[Path, str]:
    """Vectors without a time vector, the sample rate as a scalar ``fs``, phase a through
    a 100 mV/A probe."""
    from scipy.io import savemat

    savemat(path, {"fs": _rate(trace), "pos_cmd": trace.theta_ref[:, None],
                   "pos": trace.theta_m[:, None], "speed": trace.omega_m[:, None],
                   "probe_a": trace.i_a * PROBE_V_PER_A, "i_b": trace.i_b, "i_c": trace.i_c})
    return path, f"""
[time]
rate = {_rate(trace)}
[channels]
theta_ref = {{ name = "pos_cmd", unit = "rad" }}
theta_m = {{ name = "pos", unit = "rad" }}
omega_m = {{ name = "speed", unit = "rad/s" }}
i_a = {{ name = "probe_a", unit = "V", scale = "100 mV/A" }}
i_b = {{ name = "i_b", unit = "A" }}
i_c = {{ name = "i_c", unit = "A" }}
"""


def matlab_v73(trace: Trace, path: Path) -> tuple[Path, str]:
    """An HDF5 file behind MATLAB's 512-byte header, the channels in a struct ``data``
    (stored as MATLAB does: 1 x n doubles), the rate in kHz, a probe at 10 A/V."""
    import h5py

    with h5py.File(path, "w", userblock_size=512) as f:
        g = f.create_group("data")
        g.attrs["MATLAB_class"] = np.bytes_("struct")
        for name, x in (("ref", trace.theta_ref), ("theta", trace.theta_m),
                        ("w", trace.omega_m), ("ua", trace.i_a * PROBE_V_PER_A),
                        ("ib", trace.i_b), ("ic", trace.i_c)):
            ds = g.create_dataset(name, data=x[None, :])
            ds.attrs["MATLAB_class"] = np.bytes_("double")
        f.create_dataset("fs", data=np.array([[_rate(trace)]]))
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Thu Jan  1 08:00:00 2026 HDF5 schema 1.00 ."
    with open(path, "r+b") as fh:
        fh.write(header.ljust(116) + b"\x00" * 8 + b"\x00\x02IM")
    return path, f"""
[source]
group = "data"
[time]
rate = "{_rate(trace) / 1000:g} kHz"
[channels]
theta_ref = {{ name = "ref", unit = "rad" }}
theta_m = {{ name = "theta", unit = "rad" }}
omega_m = {{ name = "w", unit = "rad/s" }}
i_a = {{ name = "ua", unit = "V", scale = "10 A/V" }}
i_b = {{ name = "ib", unit = "A" }}
i_c = {{ name = "ic", unit = "A" }}
"""


def tdms(trace: Trace, path: Path) -> tuple[Path, str]:
    """One group of waveforms (``wf_increment``) with their units; the speed in rpm."""
    from nptdms import ChannelObject, TdmsWriter

    inc = 1.0 / _rate(trace)
    chans = [("Position Cmd", trace.theta_ref, "rad"), ("Position", trace.theta_m, "rad"),
             ("Speed", trace.omega_m * 60 / (2 * np.pi), "rpm"), ("IU", trace.i_a, "A"),
             ("IV", trace.i_b, "A"), ("IW", trace.i_c, "A")]
    with TdmsWriter(path) as w:
        w.write_segment([ChannelObject("Motor", name, x, properties={
            "unit_string": unit, "wf_increment": inc, "wf_start_offset": 0.0})
            for name, x, unit in chans])
    return path, """
[source]
group = "Motor"
[channels]
theta_ref = { name = "Position Cmd" }
theta_m = { name = "Position" }
omega_m = { name = "Speed" }
i_a = { name = "IU" }
i_b = { name = "IV" }
i_c = { name = "IW" }
"""


def mdf4(trace: Trace, path: Path, start: float = 5.0) -> tuple[Path, str]:
    """Two channel groups, currents and motion, each on its own master time (the logger's
    clock, ``start`` s in); the motion group is sampled at the same instants."""
    from asammdf import MDF, Signal

    t = trace.t + start
    m = MDF(version="4.10")
    m.append([Signal(trace.i_a, t, name="I_phase_A", unit="A"),
              Signal(trace.i_b, t, name="I_phase_B", unit="A"),
              Signal(trace.i_c, t, name="I_phase_C", unit="A")], acq_name="currents")
    m.append([Signal(trace.theta_ref, t, name="pos_ref", unit="rad"),
              Signal(trace.theta_m, t, name="pos_act", unit="rad"),
              Signal(trace.omega_m, t, name="n_act", unit="rad/s")], acq_name="motion")
    m.save(path, overwrite=True)
    m.close()
    return path, """
[channels]
theta_ref = { name = "pos_ref" }
theta_m = { name = "pos_act" }
omega_m = { name = "n_act" }
i_a = { name = "I_phase_A" }
i_b = { name = "I_phase_B" }
i_c = { name = "I_phase_C" }
"""


WRITERS = {"csv": (german_csv, "bench.csv"), "mat5": (matlab_v5, "bench_v5.mat"),
           "mat73": (matlab_v73, "bench_v73.mat"), "tdms": (tdms, "bench.tdms"),
           "mdf4": (mdf4, "bench.mf4")}
