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
