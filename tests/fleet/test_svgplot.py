"""The SVG chart writer of the fleet pages: known answers for its ticks and labels, its
paths and markers, escaping, and a well-formed document whatever the data."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from emaphm.fleet.svgplot import Layer, Panel, _path, _tick_label, nice_ticks, render

SVG = "{http://www.w3.org/2000/svg}"


@pytest.mark.parametrize("lo, hi, n, ticks", [
    (0.0, 1.0, 5, [0.0, 0.2, 0.4, 0.6, 0.8, 1.0]),
    (-0.03, 0.33, 6, [0.0, 0.1, 0.2, 0.3]),
    (0.0, 645.8, 4, [0.0, 200.0, 400.0, 600.0]),
    (0.0, 1.0, 4, [0.0, 0.25, 0.5, 0.75, 1.0]),
    (-4.2, 4.2, 4, [-2.5, 0.0, 2.5]),
])
def test_nice_ticks_are_round_and_inside_the_limits(lo, hi, n, ticks):
    got, step = nice_ticks(lo, hi, n)
    np.testing.assert_allclose(got, ticks, atol=1e-12)
    assert all(lo <= t <= hi for t in got)
    assert step / 10 ** math.floor(math.log10(step)) in (1.0, 2.0, 2.5, 5.0)


def test_tick_labels_show_the_digits_the_step_needs():
    assert [_tick_label(v, 0.25) for v in (0.0, 0.25, 1.0)] == ["0", "0.25", "1.00"]
    assert [_tick_label(v, 200.0) for v in (0.0, 400.0)] == ["0", "400"]
    assert _tick_label(-0.1, 0.1) == "\u22120.1"
    assert _tick_label(-1e-17, 0.1) == "0"                    # no "-0.0"
    assert _tick_label(2e6, 1e6) == "2e+06"
    # large values with a small step, small steps: as many digits as tell the ticks apart
    for lo, hi in ((1.2e6, 1.25e6), (1e6, 1e6 + 500), (0.50001, 0.50005)):
        ticks, step = nice_ticks(lo, hi, 5)
        labels = [_tick_label(v, step) for v in ticks]
        assert len(set(labels)) == len(labels) > 2, labels


def test_a_band_with_a_gap_is_two_closed_polygons_and_bad_limits_still_map():
    from emaphm.fleet.svgplot import _runs

    assert [(r.start, r.stop) for r in _runs(np.array([1, 1, 0, 1, 0, 0, 1], bool))] == \
        [(0, 2), (3, 4), (6, 7)]
    band = Panel(title="", xlim=(0.0, 4.0), ylim=(math.nan, 1.0), layers={
        "cone": Layer("band", [0, 1, 2, 3, 4], [0.1, 0.1, np.nan, 0.2, 0.2],
                      [0.5, 0.6, 0.7, 0.8, np.inf])})
    doc = render(200, 100, [(band, (20, 10, 160, 70))])
    d = next(p.get("d") for p in ET.fromstring(doc).iter(f"{SVG}path")
             if p.get("fill-opacity") == "0.18")
    assert d.count("Z") == 2 and d.count("M") == 2           # [0, 1] and [3]
    assert b"nan" not in doc and b"inf" not in doc


def test_control_characters_in_a_description_leave_the_document_well_formed():
    panel = Panel(title="ok", xlim=(0.0, 1.0), ylim=(0.0, 1.0), layers={})
    doc = render(100, 100, [(panel, (10, 10, 80, 80))], title="EMA\x1b[31m \x00 red\ufffe")
    texts = [t.text for t in ET.fromstring(doc).iter(f"{SVG}text")]
    assert "EMA\ufffd[31m \ufffd red\ufffd" in texts


def test_a_line_breaks_where_its_values_are_not_finite():
    d = _path(np.array([0.0, 1.0, 2.0, 3.0, 4.0]), np.array([0.0, 1.0, np.nan, 3.0, 4.0]))
    assert d == "M0 0L1 1M3 3L4 4"
    assert _path(np.array([np.inf]), np.array([1.0])) == ""


def test_a_document_is_well_formed_escaped_and_the_same_for_the_same_data():
    panel = Panel(title="k1 <&> \"quoted\"", xlim=(0.0, 10.0), ylim=(0.0, 1.0), layers={
        "band": Layer("band", [0, 5, 10], [0.1, 0.2, 0.3], [0.3, 0.5, 0.9], label="cone"),
        "line": Layer("line", [0, 5, 10], [0.2, np.nan, 0.6], label="trend"),
        "pts": Layer("points", [1, 2], [0.5, np.inf], color="C3", label="faulty"),
        "hol": Layer("hollow", [], []),
        "err": Layer("errorbars", [1], [0.4], [0.6], color="0.6"),
        "thr": Layer("hline", [], [0.8], color="C3", label="threshold"),
        "now": Layer("vline", [5.0], []),
        "bar": Layer("bar", [6, 9], [0.8, 0.8], color="C1", label="RUL"),
        "med": Layer("diamond", [7.5], [0.8], color="C1", label="median")},
        xlabel="time [h]", ylabel="k1 [-]", legend=True, notes=(("</text>", "top"),))
    doc = render(400, 300, [(panel, (60, 40, 320, 200))], title="EMA <script>",
                 legend=[("points", "C2", "healthy")], legend_y=20)
    root = ET.fromstring(doc)
    texts = [t.text for t in root.iter(f"{SVG}text")]
    assert "k1 <&> \"quoted\"" in texts and "EMA <script>" in texts and "</text>" in texts
    assert b"<script" not in doc
    assert len(list(root.iter(f"{SVG}circle"))) == 1 + 1 + 1   # a point, 2 legend keys
    assert doc == render(400, 300, [(panel, (60, 40, 320, 200))], title="EMA <script>",
                         legend=[("points", "C2", "healthy")], legend_y=20)
    with pytest.raises(ValueError, match="unknown layer kind 'pie'"):
        Layer("pie", [1], [1])
