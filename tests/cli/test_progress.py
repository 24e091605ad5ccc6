"""The one progress facility (:mod:`emaphm.progress`): what a terminal, a log and a quiet
run see, and the notice before Numba compiles."""

from __future__ import annotations

import io
from types import SimpleNamespace

import pytest

from emaphm import progress as P


def _state(nit, nfev, best_f=1.0):
    return SimpleNamespace(nit=nit, nfev=nfev, best_f=best_f)


def test_a_terminal_sees_one_line_redrawn_and_ended():
    buf = io.StringIO()
    line = P.SearchProgress(buf, tty=True, header="identifying with PSO (seed 0)")
    line.interval = 0.0                        # draw every state (the clock is not tested)
    for i in range(1, 4):
        line(_state(i, 50 * i, 10.0 ** -i))
    line.close()
    text = buf.getvalue()
    assert text.startswith("identifying with PSO (seed 0)\n")
    body = text[len("identifying with PSO (seed 0)\n"):]
    assert body.count("\r") == 3 and body.endswith("\n") and body.count("\n") == 1
    assert "iteration    3  best fitness 1.0000e-03     150 evaluations" in body


def test_a_log_sees_the_header_but_no_status_lines():
    buf = io.StringIO()
    line = P.SearchProgress(buf, tty=False, header="identifying with DE (seed 3)")
    for i in range(1, 50):
        line(_state(i, 10 * i))
    line.close()
    assert buf.getvalue() == "identifying with DE (seed 3)\n"


def test_quiet_shows_nothing_not_even_the_header_or_a_notice():
    buf = io.StringIO()
    line = P.SearchProgress(buf, tty=True, enabled=False, header="identifying")
    line(_state(1, 10))
    line.note("compiling")
    line.close()
    assert buf.getvalue() == ""


def test_the_header_waits_for_the_work_to_start():
    # a command refused by its checks prints only its error: the header comes with the
    # first progress (or notice), never before
    buf = io.StringIO()
    P.CountProgress("calibrating:", buf, tty=False, header="calibrating on 2 traces")
    assert buf.getvalue() == ""


def test_a_new_run_is_counted_and_restart_resets_the_count():
    buf = io.StringIO()
    line = P.SearchProgress(buf, tty=True, prefix="inspection 1/3: ")
    line.interval = 0.0
    line(_state(5, 250))
    line(_state(1, 50))                        # evaluations fell: a restart
    assert buf.getvalue().rsplit("\r", 1)[-1].startswith("inspection 1/3: run 2  iteration    1")
    line.restart("inspection 2/3: ")
    line(_state(1, 50))
    assert buf.getvalue().rsplit("\r", 1)[-1].startswith("inspection 2/3: iteration    1")


def test_a_note_clears_the_status_line_first():
    buf = io.StringIO()
    line = P.CountProgress("simulating", buf, tty=True)
    line.update(1, 4)
    line.note("a notice")
    assert buf.getvalue().endswith("\r\x1b[Ka notice\n")


def test_campaign_runs_are_logged_at_every_tenth():
    buf = io.StringIO()
    line = P.RunProgress(buf, tty=False)
    line.start(20, 0, 20)
    for i in range(20):
        line.update(SimpleNamespace(ok=i != 4))
    lines = buf.getvalue().splitlines()
    assert len(lines) == 11                    # the start and one per tenth
    assert lines[-1].startswith("runs 19/20 (95%)  failures 1  elapsed ")


def test_clock():
    assert [P.clock(s) for s in (4.4, 65, 7260)] == ["4s", "1m05s", "2h01m"]


def test_the_compile_notice_is_said_once_when_numba_compiles(monkeypatch):
    numba = pytest.importorskip("numba")
    monkeypatch.setattr(P, "_NOTICE_SAID", False)

    @numba.njit(cache=False)
    def twice(x):
        return 2 * x

    buf = io.StringIO()
    line = P.StatusLine(buf, tty=False, header="identifying with PSO (seed 0)")
    with P.compile_notice(line):
        assert twice(2) == 4                   # compiles: the notice, after the header
        assert twice(3) == 6                   # compiled: nothing more
    assert buf.getvalue() == f"identifying with PSO (seed 0)\n{P.COMPILE_NOTICE}\n"
    # once per process: a later compile says nothing
    with P.compile_notice(line):
        assert twice(2.5) == 5.0
    assert buf.getvalue().count(P.COMPILE_NOTICE) == 1


def test_no_notice_when_nothing_compiles(monkeypatch):
    numba = pytest.importorskip("numba")
    monkeypatch.setattr(P, "_NOTICE_SAID", False)

    @numba.njit(cache=False)
    def one(x):
        return x + 1

    assert one(1) == 2                          # compiled outside the block
    buf = io.StringIO()
    with P.compile_notice(P.StatusLine(buf, tty=False)):
        assert one(2) == 3
    assert buf.getvalue() == ""


# ----------------------------------------------------------------------------- a notebook
class FakeHandle:
    def __init__(self, shown):
        self.shown = shown

    def update(self, obj, raw=False):
        assert raw
        self.shown.append(("update", obj))


class FakeDisplay:
    """IPython.display as the progress uses it: display(obj, raw=True, display_id=True)
    returns a handle whose update(obj, raw=True) redraws that output."""

    def __init__(self, handles=True):
        self.shown, self.handles = [], handles

    def display(self, obj, raw=False, display_id=False):
        assert raw and display_id
        self.shown.append(("display", obj))
        return FakeHandle(self.shown) if self.handles else None


def test_a_notebook_sees_one_output_updated_in_place():
    buf = io.StringIO()
    nb = FakeDisplay()
    line = P.SearchProgress(buf, notebook=nb, header="identifying with LSQ (seed 0)")
    line.interval = 0.0
    assert line.active and not line.tty
    for i in range(1, 4):
        line(_state(i, 50 * i, 10.0 ** -i))
    line.note("a notice")
    line.close()
    kinds = [k for k, _ in nb.shown]
    assert kinds == ["display", "update", "update"]            # one output, redrawn
    texts = [obj["text/plain"] for _, obj in nb.shown]
    assert texts[0].startswith("iteration    1") and "150 evaluations" in texts[-1]
    assert all(set(obj) == {"text/plain"} for _, obj in nb.shown)   # plain text, no widget
    # the header and notices are lines of their own; no terminal escapes anywhere
    assert buf.getvalue() == "identifying with LSQ (seed 0)\na notice\n"
    assert not any("\r" in t or "\x1b" in t for t in texts)


def test_a_notebook_gets_the_last_state_at_close_and_nothing_when_quiet():
    nb = FakeDisplay()
    line = P.CountProgress("simulating trace", io.StringIO(), notebook=nb)
    line.interval = 3600.0                         # only the first state and forced ones
    line.update(1, None)
    line.update(2, None)                           # held back by the interval
    line.close()
    assert [obj["text/plain"].split(",")[0] for _, obj in nb.shown] == [
        "simulating trace 1", "simulating trace 2"]
    quiet = FakeDisplay()
    q = P.CountProgress("x", io.StringIO(), notebook=quiet, enabled=False)
    q.update(1, 2)
    q.close()
    assert quiet.shown == [] and not q.active


def test_a_notebook_display_without_handles_falls_back_to_plain_lines():
    buf = io.StringIO()
    nb = FakeDisplay(handles=False)
    line = P.CountProgress("calibrating:", buf, notebook=nb, noun=" model runs")
    for i in range(1, 21):
        line.update(i, 20)
    line.close()
    assert len(nb.shown) == 1                      # tried once
    lines = buf.getvalue().splitlines()
    assert lines[0].startswith("calibrating: 1/20 model runs")
    assert lines[-1].startswith("calibrating: 20/20 model runs") and len(lines) <= 11


def test_the_notebook_is_found_in_a_kernel_and_not_in_a_terminal_ipython(monkeypatch):
    import sys
    import types

    display = types.ModuleType("IPython.display")
    ipython = types.ModuleType("IPython")
    ipython.display = display
    shell = SimpleNamespace()
    ipython.get_ipython = lambda: shell
    monkeypatch.setitem(sys.modules, "IPython", ipython)
    monkeypatch.setitem(sys.modules, "IPython.display", display)
    assert P.notebook_display() is None                     # a terminal IPython: no kernel
    shell.kernel = object()
    assert P.notebook_display() is display
    assert P.StatusLine().notebook is display               # found by default
    assert P.StatusLine(io.StringIO()).notebook is None     # an explicit stream is kept
    assert P.StatusLine(tty=True).notebook is None
    ipython.get_ipython = lambda: None                      # IPython imported, no shell
    assert P.notebook_display() is None
    monkeypatch.delitem(sys.modules, "IPython")
    assert P.notebook_display() is None
