"""What the importers' readers make of odd exports (``emaphm import``): CSV exports with
text columns and units the table lacks, a map's unit or delimiter that contradicts the file, MATLAB structs in
structs, struct arrays and matrices, TDMS channels at two rates, a gap in the time, a
column named twice, and errors from Python that name the map's file. Each test builds a
small file and checks the numbers or the message."""

from __future__ import annotations

import re
import tomllib

import numpy as np
import pytest

from emaphm.cli import main
from emaphm.traces import TraceError
from emaphm.traces.importers import (ChannelMap, MapError, describe, import_trace,
                                     inspect_source, load_map, starter_map)

N = 400                                     # rows: 40 ms at 10 kHz


def _map(text: str) -> ChannelMap:
    return ChannelMap.from_dict(tomllib.loads(text), source="map.toml")


def _signals():
    t = np.arange(N) * 1e-4
    ref = 8.0 * np.sin(2 * np.pi * 5 * t)               # rad: over a turn, as validation asks
    pos = ref - 0.01
    ia, ib = np.cos(2 * np.pi * 50 * t), np.sin(2 * np.pi * 50 * t)
    return t, ref, pos, ia, ib


def _german(path, header, *, units=None, extra=None, delimiter=";", preamble=True):
    """``;`` and decimal commas: t in ms, positions in degrees, two currents in A, then
    the ``extra`` column's cells (one per row) where given."""
    t, ref, pos, ia, ib = _signals()
    data = np.column_stack([t * 1e3, np.degrees(ref), np.degrees(pos), ia, ib])
    lines = ["# Pr\u00fcfstand 3", "# exportiert 2024-05-03"] if preamble else []
    lines += [delimiter.join(header)] + ([delimiter.join(units)] if units else [])
    for k, row in enumerate(data):
        cells = [repr(float(x)).replace(".", ",") for x in row]
        if extra is not None:
            cells.append(extra[k])
        lines.append(delimiter.join(cells))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


_HEADER = ["Zeit [ms]", "Soll [\u00b0]", "Ist [\u00b0]", "IU [A]", "IV [A]"]
_MAP = ('[channels]\nt = { name = "Zeit" }\ntheta_ref = { name = "Soll" }\n'
        'theta_m = { name = "Ist" }\ni_a = { name = "IU" }\ni_b = { name = "IV" }\n')


def _check(trace):
    t, ref, _, ia, ib = _signals()
    assert trace.n == N
    np.testing.assert_allclose(trace.t, t, atol=1e-12)
    np.testing.assert_allclose(trace.theta_ref, ref, atol=1e-12)
    np.testing.assert_allclose(trace.i_a, ia, atol=1e-12)
    np.testing.assert_allclose(trace.i_b, ib, atol=1e-12)


# ----------------------------------------------------------------------------- defect 3
def test_a_text_column_is_listed_as_text_and_not_read(tmp_path, capsys):
    src = _german(tmp_path / "run.csv", _HEADER + ["Status"],
                  extra=["RUN" if k % 2 else "OK" for k in range(N)])
    info = inspect_source(src)
    assert [c.name for c in info.channels] == ["Zeit", "Soll", "Ist", "IU", "IV", "Status"]
    assert info.channels[-1].text == "OK" and info.channels[0].text is None
    assert "Status          (text)" in describe(info)
    assert "text, not read: 'Status'" in describe(info)
    assert "#   'Status' (text, not read)" in starter_map(info)
    _check(import_trace(src, _map(_MAP)))
    assert main(["import", str(src), "--inspect"]) == 0            # and the starter map imports
    _check(import_trace(src, _map(capsys.readouterr().out)))
    with pytest.raises(TraceError, match=r"^map.toml: \[channels\] i_b: column 'Status' holds "
                                         r"text, not numbers \(e.g. 'OK'\); map a column of "
                                         r"numbers$"):
        import_trace(src, _map(_MAP.replace('"IV"', '"Status", unit = "A"')))


def test_an_event_column_with_text_in_the_first_row_only_keeps_the_header(tmp_path):
    src = _german(tmp_path / "run.csv", _HEADER + ["Ereignis"],
                  extra=["Start"] + [""] * (N - 1))
    info = inspect_source(src)
    assert [c.name for c in info.channels][:2] == ["Zeit", "Soll"]
    assert info.channels[-1].text == "Start"
    _check(import_trace(src, _map(_MAP)))                             # the first row is data


def test_a_preamble_of_name_and_number_lines_is_not_taken_for_data(tmp_path):
    # rows with text beside numbers are data only where the last rows have text there too
    t, ref, pos, ia, ib = _signals()
    rows = np.column_stack([t, ref, pos, ia, ib])
    (tmp_path / "kv.csv").write_text("Rate;10000\nKan\u00e4le;5\nScale;1\nOffset;0\nt;r;m;a;b\n"
                                     + "\n".join(";".join(repr(float(x)) for x in row)
                                                 for row in rows) + "\n")
    info = inspect_source(tmp_path / "kv.csv")
    assert [c.name for c in info.channels] == ["t", "r", "m", "a", "b"]
    assert "4 line(s) of preamble" in describe(info)


# ----------------------------------------------------------------------------- defect 4
@pytest.mark.parametrize("temp", ["degC", "\u00b0C"])
def test_a_units_row_with_a_unit_the_table_lacks(tmp_path, temp):
    src = _german(tmp_path / "run.txt", ["Zeit", "Soll", "Ist", "IU", "IV", "Temp"],
                  units=["ms", "deg", "deg", "A", "A", temp], delimiter="\t", preamble=False,
                  extra=[f"{25 + 0.05 * k:.2f}".replace(".", ",") for k in range(N)])
    info = inspect_source(src)
    assert [c.name for c in info.channels] == ["Zeit", "Soll", "Ist", "IU", "IV", "Temp"]
    assert [c.unit for c in info.channels] == ["ms", "deg", "deg", "A", "A", temp]
    _check(import_trace(src, _map(_MAP)))
    # mapped, the unit the table lacks is refused by name, or the map's unit is used
    with pytest.raises(MapError, match=rf"\[channels\] theta_m: the file declares unit "
                                       rf"'{temp}' for channel 'Temp', not one emaphm knows; "
                                       r"give its unit in the map"):
        import_trace(src, _map(_MAP.replace('"Ist"', '"Temp"')))
    back = import_trace(src, _map(_MAP.replace('"Ist" }', '"Temp", unit = "rad" }')))
    np.testing.assert_allclose(back.theta_m, 25 + 0.05 * np.arange(N), atol=1e-12)


# ----------------------------------------------------------------------------- defect 5
def test_a_map_unit_that_contradicts_the_file_is_refused(tmp_path):
    src = _german(tmp_path / "run.csv", _HEADER)
    with pytest.raises(MapError, match=r"^map.toml: \[channels\] i_a: channel 'IU' is declared "
                                       r"in 'A' by the file, in 'mA' by the map; remove unit "
                                       r"from the map to read it in A, or, where the file's "
                                       r"unit is wrong, remove unit and give scale = 0.001"):
        import_trace(src, _map(_MAP.replace('"IU"', '"IU", unit = "mA"')))
    with pytest.raises(MapError, match=r"\[channels\] t: channel 'Zeit' is declared in 'ms' by "
                                       r"the file, in 'us' by the map"):
        import_trace(src, _map(_MAP.replace('"Zeit"', '"Zeit", unit = "us"')))
    # the same unit spelt otherwise is no contradiction
    _check(import_trace(src, _map(_MAP.replace('"Soll"', '"Soll", unit = "deg"')
                                  .replace('"IU"', '"IU", unit = "[A]"'))))
    # the advice works: the file's unit with the scale of the map's
    back = import_trace(src, _map(_MAP.replace('"IU"', '"IU", scale = 0.001')))
    np.testing.assert_allclose(back.i_a, _signals()[3] * 1e-3, atol=1e-15)


# ----------------------------------------------------------------------------- defect 7
def _mat_channels(t):
    _, ref, pos, ia, ib = _signals()
    return {"zeit_ms": t * 1e3, "soll": ref, "ist": pos, "iu": ia, "iv": ib}


_MAT_MAP = ('[channels]\nt = { name = "zeit_ms", group = "GROUP", unit = "ms" }\n'
            'theta_ref = { name = "soll", group = "GROUP", unit = "rad" }\n'
            'theta_m = { name = "ist", group = "GROUP", unit = "rad" }\n'
            'i_a = { name = "iu", group = "GROUP", unit = "A" }\n'
            'i_b = { name = "iv", group = "GROUP", unit = "A" }\n')


def test_matlab_struct_in_a_struct_is_the_group_run_dot_field(tmp_path):
    from scipy.io import savemat

    t = _signals()[0]
    savemat(tmp_path / "run.mat", {"Run": {"Info": {"fs": 10000.0},
                                           "Messung": _mat_channels(t)}})
    info = inspect_source(tmp_path / "run.mat")
    assert {c.group for c in info.channels} == {"Run.Messung"}
    assert "Run.Info.fs = 10000" in describe(info)
    _check(import_trace(tmp_path / "run.mat", _map(_MAT_MAP.replace("GROUP", "Run.Messung"))))
    with pytest.raises(TraceError, match=r"no channel 'zeit_ms' in group 'Run' in run.mat "
                                         r"\(did you mean 'Run.Messung/zeit_ms'\?\)"):
        import_trace(tmp_path / "run.mat", _map(_MAT_MAP.replace("GROUP", "Run")))


def test_matlab_v73_struct_in_a_struct_reads_by_its_dotted_or_its_hdf5_path(tmp_path):
    """Version 7.3 (HDF5) lists a nested struct as Run.Messung, as version 5 does; a map
    written before, with the HDF5 path Run/Messung, still reads it."""
    h5py = pytest.importorskip("h5py")
    t = _signals()[0]
    with h5py.File(tmp_path / "run73.mat", "w", userblock_size=512) as f:
        g = f.create_group("Run").create_group("Messung")
        for name, x in _mat_channels(t).items():
            g.create_dataset(name, data=x[None, :])
    assert {c.group for c in inspect_source(tmp_path / "run73.mat").channels} == {"Run.Messung"}
    for group in ("Run.Messung", "Run/Messung"):
        _check(import_trace(tmp_path / "run73.mat", _map(_MAT_MAP.replace("GROUP", group))))


def test_matlab_struct_array_and_matrix_say_why_they_are_not_read(tmp_path, capsys):
    from scipy.io import savemat

    t = _signals()[0]
    runs = np.empty((1, 2), dtype=[(k, object) for k in _mat_channels(t)])
    for j in range(2):
        for k, v in _mat_channels(t).items():
            runs[0, j][k] = v
    savemat(tmp_path / "sa.mat", {"Messung": runs})
    savemat(tmp_path / "m.mat", {"data": np.column_stack(list(_mat_channels(t).values()))})
    save = "save each channel as a vector, at the top level or in a struct"
    for name, why in (("sa.mat", f"variable 'Messung' is a struct array of 2, not read; {save}"),
                      ("m.mat", f"variable 'data' is a 2-D matrix of {N} x 5, not read; {save}")):
        assert main(["import", str(tmp_path / name), "--inspect"]) == 0
        out = capsys.readouterr().out
        assert f"# {why}" in out and "(no numeric channels found)" in out
        with pytest.raises(TraceError, match=r"the file has no channel it can read; "
                                             + why.replace("(", r"\(").replace(")", r"\)")):
            import_trace(tmp_path / name, _map(_MAT_MAP.replace("GROUP", "Messung")))


# ----------------------------------------------------------------------------- defect 9
def test_a_gap_in_the_time_is_named_where_it_is(tmp_path):
    t, ref, pos, ia, ib = _signals()
    keep = np.r_[0:250, 300:N]                                      # 50 rows lost at 25 ms
    rows = np.column_stack([t, ref, pos, ia, ib])[keep]
    (tmp_path / "gap.csv").write_text("t,r,m,a,b\n" + "\n".join(
        ",".join(repr(float(x)) for x in row) for row in rows) + "\n")
    cmap = _map('[channels]\nt = {name = "t", unit = "s"}\ntheta_ref = {name = "r", unit = "rad"}\n'
                'theta_m = {name = "m", unit = "rad"}\ni_a = {name = "a", unit = "A"}\n'
                'i_b = {name = "b", unit = "A"}\n')
    with pytest.raises(TraceError, match=r"the time base has a gap of 0.0051 s \(about 50 "
                                         r"samples missing\) between rows 249 and 250 of the "
                                         r"window \(t = 0.0249 s to 0.03 s\), where the other "
                                         r"steps are about 0.0001 s; import a window before or "
                                         r"after it \(--window START:END\)"):
        import_trace(tmp_path / "gap.csv", cmap)


# ----------------------------------------------------------------------------- defect 10
def test_a_map_delimiter_or_decimal_the_file_does_not_use_is_named(tmp_path):
    src = _german(tmp_path / "run.csv", _HEADER)
    with pytest.raises(TraceError, match=r"run.csv: with delimiter ',' from the map no row "
                                         r"splits into numbers; the file looks like ';' between "
                                         r"the fields with decimal comma: remove \[source\] "
                                         r"delimiter or set it to ';'$"):
        import_trace(src, _map('[source]\ndelimiter = ","\n' + _MAP))
    with pytest.raises(TraceError, match=r"run.csv: with decimal '.' from the map .*; the file "
                                         r"looks like ';' between the fields with decimal "
                                         r"comma: remove \[source\] decimal or set it to ','$"):
        import_trace(src, _map('[source]\ndecimal = "."\n' + _MAP))
    _check(import_trace(src, _map('[source]\ndelimiter = ";"\ndecimal = ","\n' + _MAP)))


# ----------------------------------------------------------------------------- defect 13
def test_tdms_channels_at_two_rates_are_named_with_their_rates(tmp_path, capsys):
    pytest.importorskip("nptdms")
    from nptdms import ChannelObject, TdmsWriter

    _, ref, pos, ia, ib = _signals()
    with TdmsWriter(tmp_path / "two.tdms") as w:
        w.write_segment([ChannelObject("G", name, x, properties={
            "unit_string": unit, "wf_increment": inc, "wf_start_offset": 0.0})
            for name, x, unit, inc in (("Soll", ref[::2], "rad", 2e-4), ("Ist", pos[::2], "rad", 2e-4),
                                       ("IU", ia, "A", 1e-4), ("IV", ib, "A", 1e-4))])
    assert main(["import", str(tmp_path / "two.tdms"), "--inspect"]) == 0
    out = capsys.readouterr().out
    assert "#   5000 Hz: G/Soll, G/Ist\n#   10000 Hz: G/IU, G/IV" in out and "rate = 0" not in out
    cmap = _map('[source]\ngroup = "G"\n[channels]\ntheta_ref = "Soll"\ntheta_m = "Ist"\n'
                'i_a = "IU"\ni_b = "IV"\n')
    with pytest.raises(TraceError, match=r"the channels mapped have time bases at different "
                                         r"rates \('G/Soll' and 'G/Ist' at 5000 Hz; 'G/IU' and "
                                         r"'G/IV' at 10000 Hz\); emaphm needs them on one time "
                                         r"base"):
        import_trace(tmp_path / "two.tdms", cmap)


# ----------------------------------------------------------------------------- defect 14
def test_a_column_named_twice_is_named_with_its_columns(tmp_path):
    src = _german(tmp_path / "run.csv", _HEADER[:4] + ["IU [A]"])
    with pytest.raises(TraceError, match=r"^map.toml: \[channels\] i_a: column 'IU' appears 2 "
                                         r"times in the header of run.csv \(columns 4 and 5\); "
                                         r"rename one in the file$"):
        import_trace(src, _map(_MAP))


# ----------------------------------------------------------------------------- defect 15
def test_a_cell_that_is_not_a_number_gets_advice_that_works(tmp_path):
    src = _german(tmp_path / "run.csv", _HEADER)
    lines = src.read_text().splitlines()
    lines[3 + 100] = lines[3 + 100].rsplit(";", 1)[0] + ";1,2,3"
    src.write_text("\n".join(lines) + "\n")
    with pytest.raises(TraceError, match=r"cannot read the data as numbers in data row 100, "
                                         r"column 'IV' \(the value '1,2,3'\).*: correct that "
                                         r"value in the file, or remove its row$") as err:
        import_trace(src, _map(_MAP))
    assert "nan" not in str(err.value)


# ----------------------------------------------------------------------------- defect 16
def test_errors_from_a_loaded_map_name_its_file(tmp_path):
    src = _german(tmp_path / "run.csv", _HEADER)
    (tmp_path / "rig.toml").write_text(_MAP.replace('"IV"', '"I_V"'))
    cmap = load_map(tmp_path / "rig.toml")
    with pytest.raises(TraceError, match=rf"^{re.escape(str(tmp_path / 'rig.toml'))}: "
                                         r"\[channels\] i_b: no channel 'I_V' in run.csv"):
        import_trace(src, cmap)
    with pytest.raises(TraceError, match=r"^other.toml: \[channels\] i_b"):
        import_trace(src, cmap, map_name="other.toml")
    assert cmap == _map(_MAP.replace('"IV"', '"I_V"'))           # where it came from aside


# ----------------------------------------------------------------------------- second review
def test_a_sensor_declared_in_volts_is_read_through_the_maps_unit_and_scale(tmp_path):
    """A DAQ labels every input V: a potentiometer at 36 deg/V is mapped with unit = "deg"
    and scale = 36. The file's unit is of another quantity, so the map's is no contradiction
    (the refusal of contradicting units, same quantity, refused this)."""
    t, ref, pos, ia, ib = _signals()
    volts = np.degrees(np.column_stack([ref, pos])) / 36.0
    lines = ["t [s],ref [V],pos [V],ia [A],ib [A]"] + [
        ",".join(repr(float(x)) for x in row)
        for row in np.column_stack([t, volts, ia, ib])]
    (tmp_path / "daq.csv").write_text("\n".join(lines) + "\n")
    cmap = _map('[channels]\nt = { name = "t" }\n'
                'theta_ref = { name = "ref", unit = "deg", scale = 36 }\n'
                'theta_m = { name = "pos", unit = "deg", scale = 36 }\n'
                'i_a = { name = "ia" }\ni_b = { name = "ib" }\n')
    _check(import_trace(tmp_path / "daq.csv", cmap))


def test_a_contradicting_unit_with_an_offset_is_not_given_a_scale_that_drops_it(tmp_path):
    src = _german(tmp_path / "run.csv", _HEADER)
    with pytest.raises(MapError) as err:
        import_trace(src, _map(_MAP.replace('"IU"', '"IU", unit = "mA", offset = 5')))
    assert "in 'mA' by the map; remove unit from the map to read it in A" in str(err.value)
    assert "scale" not in str(err.value)


def test_a_long_preamble_of_names_and_numbers_is_not_taken_for_data(tmp_path):
    """Catman-like: 25 lines 'ParamK,value' above the header. Rows of data start with a
    number; a preamble's line starts with its name (the header was line 1)."""
    t, _, _, ia, _ = _signals()
    lines = [f"Param{k},{0.5 * k}" for k in range(25)] + ["t,i_a,omega"]
    lines += [f"{float(x)!r},{float(y)!r},1.0" for x, y in zip(t[:30], ia[:30])]
    (tmp_path / "pre.csv").write_text("\n".join(lines) + "\n")
    info = inspect_source(tmp_path / "pre.csv")
    assert [c.name for c in info.channels] == ["t", "i_a", "omega"]
    assert "header on line 26" in describe(info)


def test_a_first_data_row_of_ones_and_text_is_not_a_units_row(tmp_path):
    (tmp_path / "ones.csv").write_text("n,enable,state\n" + "".join(
        f"{k + 1},1,{'RUN' if k % 2 else 'OK'}\n" for k in range(10)))
    info = inspect_source(tmp_path / "ones.csv")
    assert [(c.name, c.unit) for c in info.channels][:2] == [("n", None), ("enable", None)]
    assert "units" not in describe(info).splitlines()[0]


def test_rows_of_integers_say_nothing_of_the_decimal(tmp_path):
    """The first rows sniffed hold integers only: they show no decimal separator, so a
    map's decimal comma is not contradicted (a refusal said to set it to '.', which would
    break the rows further down)."""
    rows = ["t;a;b"] + [f"{k};0;0" for k in range(30)] + [f"{k};0,5;1,25" for k in range(30, 60)]
    (tmp_path / "int.csv").write_text("\n".join(rows) + "\n")
    with pytest.raises(TraceError) as err:
        import_trace(tmp_path / "int.csv", _map('[source]\ndecimal = ","\n[channels]\n'
                                                't = { name = "t", unit = "ms" }\n'
                                                'theta_ref = { name = "x", unit = "rad" }\n'
                                                'theta_m = { name = "a", unit = "rad" }\n'
                                                'i_a = { name = "a", unit = "A" }\n'
                                                'i_b = { name = "b", unit = "A" }\n'))
    assert "no channel 'x'" in str(err.value) and "decimal" not in str(err.value)


# ----------------------------------------------------------------------------- issue 37
def test_a_channel_named_group_slash_channel_is_read_as_in_group_or_in_its_name(tmp_path):
    """The documented "GROUP/CHANNEL" form, as --inspect lists a channel, and the name
    with its group: both read the same channels (it was refused with "no channel 'EMA/Time'
    ...; the file has 'EMA/Time'")."""
    pytest.importorskip("nptdms")
    from nptdms import ChannelObject, TdmsWriter

    t, ref, pos, ia, ib = _signals()
    with TdmsWriter(tmp_path / "rig.tdms") as w:
        w.write_segment([ChannelObject("EMA", name, x, properties={"unit_string": unit})
                         for name, x, unit in (("Time", t, "s"), ("Soll", ref, "rad"),
                                               ("Ist", pos, "rad"), ("IU", ia, "A"),
                                               ("IV", ib, "A"))])
        w.write_segment([ChannelObject("Other", "Time", t[::-1], properties={"unit_string": "s"})])
    slash = _map('[channels]\nt = "EMA/Time"\ntheta_ref = "EMA/Soll"\ntheta_m = "EMA/Ist"\n'
                 'i_a = "EMA/IU"\ni_b = { name = "EMA/IV", group = "EMA" }\n')
    grouped = _map('[source]\ngroup = "EMA"\n[channels]\nt = "Time"\ntheta_ref = "Soll"\n'
                   'theta_m = "Ist"\ni_a = "IU"\ni_b = "IV"\n')
    for cmap in (slash, grouped):
        _check(import_trace(tmp_path / "rig.tdms", cmap))
    with pytest.raises(TraceError, match=r"no channel 'EMA/IV' in group 'Other' in rig.tdms"):
        import_trace(tmp_path / "rig.tdms", _map(
            '[channels]\nt = "EMA/Time"\ntheta_ref = "EMA/Soll"\ntheta_m = "EMA/Ist"\n'
            'i_a = "EMA/IU"\ni_b = { name = "EMA/IV", group = "Other" }\n'))


def test_inspect_of_a_truncated_file_lists_what_it_can_and_says_it_is_truncated(tmp_path, capsys):
    """A MATLAB 5 file cut in its fifth variable: --inspect lists the four before it with
    one warning line, and says so in the map it prints; an import refuses it (the
    bad-input corpus)."""
    from scipy.io import savemat

    t, ref, pos, ia, ib = _signals()
    savemat(tmp_path / "run.mat", {"fs": 1e4, "ref": ref, "pos": pos, "ia": ia, "ib": ib})
    data = (tmp_path / "run.mat").read_bytes()
    (tmp_path / "cut.mat").write_bytes(data[:len(data) - 1000])
    assert main(["import", str(tmp_path / "cut.mat"), "--inspect"]) == 0
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1
    assert captured.err.startswith(f"emaphm import: warning: {tmp_path / 'cut.mat'}: the file "
                                   "is truncated (or a length in it is damaged): variable 5 (at "
                                   "byte ")
    assert "the 4 variable(s) before it are whole" in captured.err
    assert "listed below: what of it can be read" in captured.err
    assert "# damaged: the file is truncated" in captured.out
    assert [c.name for c in inspect_source(tmp_path / "cut.mat").channels] == ["ref", "pos", "ia"]


def test_inspect_of_a_file_with_a_line_break_in_its_names_prints_valid_toml(tmp_path, capsys):
    """A line break in the file's name broke the TOML --inspect prints; the command line
    it suggests is quoted for the shell."""
    t, ref, pos, ia, ib = _signals()
    rows = "\n".join(",".join(repr(float(x)) for x in r) for r in zip(t, ref, pos, ia, ib))
    odd = tmp_path / "run 1\nb.csv"
    odd.write_text("t,ref,pos,ia,ib\n" + rows + "\n")
    spaced = tmp_path / "run 2 (bench).csv"
    spaced.write_text("t,ref,pos,ia,ib\n" + rows + "\n")
    for path in (odd, spaced):
        assert main(["import", str(path), "--inspect"]) == 0
        out = capsys.readouterr().out
        tomllib.loads(out)                              # the whole output is TOML
    assert "#   emaphm import 'run 2 (bench).csv' --map THIS.toml" in out
