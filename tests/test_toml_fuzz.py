"""Property-based tests of the TOML readers (issue 25): any bytes given as a parameter
file, a tolerance file or a channel map are read, or refused with a one-line error of the
reader's own kind that names the file; no other exception escapes.

The bytes are drawn as a valid file of each kind with edits of the kinds hands and tools
make (a line cut, a value replaced by text, a number by an extreme or a non-finite one, a
section repeated, bytes of another encoding, random bytes inserted), and as raw bytes.
"""

from __future__ import annotations


import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from emaphm.params import ParameterError, load_params, save_params, siemens_1fk7060
from emaphm.traces.importers import MapError
from emaphm.traces.importers.channel_map import load_map
from emaphm.units import load_tolerances


@pytest.fixture(scope="module")
def valid(tmp_path_factory):
    d = tmp_path_factory.mktemp("valid")
    params = save_params(siemens_1fk7060(), d / "p.toml").read_text()
    params += "\n[thresholds]\nfriction = 0.07\nshort_circuit = 0.012\n"
    tol = "[tolerances]\nJ = [-0.1, 0.1]\nflux = [-0.05, 0.05]\nsensor_offset = [-0.02, 0.02]\n"
    cmap = ('[channels]\n'
            'theta_ref = { name = "Soll", unit = "deg" }\n'
            'theta_m = { name = "Ist", unit = "deg" }\n'
            'i_a = { name = "Ia", unit = "A" }\ni_b = { name = "Ib", unit = "mA" }\n'
            '[time]\nrate = 8000\n')
    return {"params": params, "tolerances": tol, "map": cmap}


_VALUES = st.sampled_from(["nan", "inf", "-inf", "1e308", "-1e308", "0", "-1", "1e-320", '"x"',
                           "[]", "{}", "true", "[1, 2]", '"1.5 ohm"', "", "=", "[[x]]"])


@st.composite
def edited(draw, text: str) -> bytes:
    lines = text.splitlines()
    for _ in range(draw(st.integers(1, 4))):
        if not lines:
            break
        i = draw(st.integers(0, len(lines) - 1))
        kind = draw(st.sampled_from(["cut", "value", "dup", "junk", "truncate", "section"]))
        if kind == "cut":
            del lines[i]
        elif kind == "value" and "=" in lines[i]:
            key = lines[i].split("=", 1)[0]
            lines[i] = f"{key}= {draw(_VALUES)}"
        elif kind == "dup":
            lines.insert(i, lines[i])
        elif kind == "junk":
            lines[i] = lines[i] + draw(st.text(max_size=6))
        elif kind == "truncate":
            lines = lines[:i]
        elif kind == "section":
            lines.insert(i, draw(st.sampled_from(["[motor]", "[thresholds]", "[x]", "[channels]",
                                                  "[tolerances]", "[[motor]]"])))
    encoding = draw(st.sampled_from(["utf-8", "utf-8", "utf-16", "latin-1"]))
    return "\n".join(lines).encode(encoding, errors="replace")


READERS = {"params": (load_params, ParameterError, "parameter file"),
           "tolerances": (load_tolerances, ValueError, ""),
           "map": (load_map, MapError, "channel map")}


def _read_or_refuse(kind: str, path, raw: bytes) -> None:
    read, error, _ = READERS[kind]
    path.write_bytes(raw)
    try:
        read(path)
    except error as exc:
        text = str(exc)
        assert text.strip() and "Traceback" not in text
        assert str(path.name) in text, text           # names the file
    assert path.read_bytes() == raw                   # reading changes nothing


@pytest.mark.parametrize("kind", sorted(READERS))
def test_the_valid_files_read(valid, tmp_path, kind):
    p = tmp_path / "f.toml"
    p.write_text(valid[kind])
    READERS[kind][0](p)


@pytest.mark.filterwarnings("ignore")
@settings(max_examples=400, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(data=st.data(), kind=st.sampled_from(sorted(READERS)))
def test_an_edited_toml_file_is_read_or_refused_in_one_line(valid, tmp_path_factory, data, kind):
    raw = data.draw(edited(valid[kind]))
    _read_or_refuse(kind, tmp_path_factory.mktemp("fuzz") / "edited.toml", raw)


@pytest.mark.filterwarnings("ignore")
@settings(max_examples=300, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(raw=st.binary(max_size=300), kind=st.sampled_from(sorted(READERS)))
def test_any_bytes_are_read_or_refused_in_one_line(tmp_path_factory, raw, kind):
    _read_or_refuse(kind, tmp_path_factory.mktemp("fuzz") / "raw.toml", raw)


def test_a_parameter_file_with_a_non_finite_value_is_refused_by_name(valid, tmp_path):
    p = tmp_path / "p.toml"
    p.write_text(valid["params"].replace("J_m = ", "J_m = nan # ", 1))
    with pytest.raises(ParameterError, match="J_m"):
        load_params(p)
