"""The progress bar by default: shown where someone watches (a terminal on stderr, or a
notebook) for a call estimated to take a few seconds or more; never with progress=False,
always with progress=True, never where stderr is a file or a pipe unless asked for."""

import io
import sys

import numpy as np
import pytest

import pendula
from pendula import dense


class Tty(io.StringIO):
    def isatty(self):
        return True


def test_the_decision_rule():
    # The default (None): a bar where watched and the call is estimated at 3 s or more.
    assert dense.show_bar(None, 59.0, True)
    assert dense.show_bar(None, dense.AUTO_SECONDS, True)
    assert not dense.show_bar(None, 0.9 * dense.AUTO_SECONDS, True)
    assert not dense.show_bar(None, 59.0, False), "not in a pipe or a file"
    # True always, False never.
    assert dense.show_bar(True, 0.0, False) and dense.show_bar(True, 59.0, True)
    assert not dense.show_bar(False, 59.0, True) and not dense.show_bar(False, 0.0, False)
    # The estimate: elapsed / fraction done; the elapsed time (a lower bound) when unknown.
    assert dense.estimate_seconds(0.5, 0.01) == pytest.approx(50.0)
    assert dense.estimate_seconds(2.0, 1.0) == 2.0
    assert dense.estimate_seconds(4.0, None) == 4.0 and dense.estimate_seconds(4.0, 0.0) == 4.0


def test_watched_means_a_terminal_or_a_notebook(monkeypatch):
    assert dense.interactive(Tty())
    assert not dense.interactive(io.StringIO())
    # Under pytest stderr is captured: no terminal, no kernel.
    assert not dense.interactive()

    class Kernel:
        kernel = object()

    class FakeIPython:
        @staticmethod
        def get_ipython():
            return Kernel()

    monkeypatch.setitem(sys.modules, "IPython", FakeIPython)
    monkeypatch.setitem(sys.modules, "ipykernel", object())
    assert dense.interactive(io.StringIO())
    FakeIPython.get_ipython = staticmethod(lambda: None)  # a plain IPython shell: no kernel
    assert not dense.interactive(io.StringIO())


def test_an_auto_bar_appears_only_once_the_estimate_calls_for_it(capfd, monkeypatch):
    """A lazy bar with a fake clock: silent while the run is young or its estimate short,
    drawn from the moment the estimate reaches 3 s, and nothing at all for a short run."""
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)  # the line on stderr, without tqdm
    now = [0.0]
    bar = dense.Progress(0, 100, unit="members", label=None, auto=True, clock=lambda: now[0])
    now[0] = 0.2
    bar(50)  # too early to judge, though it would be short
    now[0] = 0.6
    bar(60)  # 1 s estimated
    bar.close(100)
    assert capfd.readouterr().err == ""

    now[0] = 0.0
    bar = dense.Progress(0, 100, unit="members", label=None, auto=True, clock=lambda: now[0])
    now[0] = 0.6
    bar(10)  # 6 s estimated
    bar.close(100)
    err = capfd.readouterr().err
    assert "100 of 100 members" in err, err


def long_calls():
    """Calls that take a few tenths of a second: with the threshold lowered they are 'long'."""
    y0s = np.zeros((8000, 4))
    y0s[:, 0] = np.linspace(-3, 3, 8000)
    return {
        "solve": lambda **kw: pendula.solve("double", (0, 300), method="gauss-legendre-4", dt=1e-3, **kw),
        "ensemble": lambda **kw: pendula.ensemble("double", y0s, steps=2000, dt=1e-3, threads=1, **kw),
        "sweep": lambda **kw: pendula.sweep("double", ["theta1=-3:3:100", "theta2=-3:3:100"], steps=2000, threads=1, **kw),
        "fractal": lambda **kw: pendula.fractal(theta1=(-3, 3, 60), theta2=(-3, 3, 60), t_max=20, threads=1, **kw),
    }


@pytest.mark.parametrize("name", ["solve", "ensemble", "sweep", "fractal"])
def test_progress_false_prints_nothing_where_the_default_shows_a_bar(name, capfd, monkeypatch):
    # Someone watches, and anything over 0.1 s (estimated after 0.05 s) counts as long.
    monkeypatch.setattr(dense, "interactive", lambda stream=None: True)
    monkeypatch.setattr(dense, "AUTO_SECONDS", 0.1)
    monkeypatch.setattr(dense, "AUTO_AFTER", 0.05)
    call = long_calls()[name]
    call()
    shown = capfd.readouterr().err
    assert shown.strip(), f"{name}: the default shows a bar on a long call where watched"
    call(progress=False)
    assert capfd.readouterr() == ("", ""), f"{name}: progress=False prints nothing"


def test_no_bar_by_default_where_stderr_is_not_a_terminal(capfd, monkeypatch):
    # The same long call, stderr captured (not a terminal, not a notebook): silent.
    monkeypatch.setattr(dense, "AUTO_SECONDS", 0.1)
    monkeypatch.setattr(dense, "AUTO_AFTER", 0.05)
    long_calls()["solve"]()
    assert capfd.readouterr().err == ""
    # Unless asked for.
    long_calls()["solve"](progress=True)
    assert capfd.readouterr().err.strip()


def test_a_short_call_shows_no_bar_by_default_even_where_watched(capfd, monkeypatch):
    monkeypatch.setattr(dense, "interactive", lambda stream=None: True)
    pendula.solve("double", (0, 1), method="rk4")
    pendula.ensemble("double", np.zeros((100, 4)), steps=10)
    assert capfd.readouterr().err == ""


def test_a_backward_run_bar_counts_the_time_run(capfd, monkeypatch):
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)  # the line on stderr, without tqdm
    seen = []
    pendula.solve("double", (60, 0), method="dop853", rtol=1e-12, atol=1e-12, progress=seen.append)
    assert seen[-1] == 0.0 and seen == sorted(seen, reverse=True) and all(0 <= t <= 60 for t in seen)
    bar = dense.Progress(10, 0, unit="s")
    bar(7.5)
    bar.close(0.0)
    err = capfd.readouterr().err
    assert "25.0%  t = 7.5 s" in err and "100.0%  t = 0 s" in err, err


def test_an_invalid_progress_names_the_argument():
    with pytest.raises(pendula.InvalidValueError, match="for `progress`: None"):
        pendula.solve("double", (0, 1), progress="yes")
    with pytest.raises(pendula.InvalidValueError, match="for `progress`: None"):
        pendula.ensemble("double", np.zeros((3, 4)), steps=3, progress=2)


def test_studies_say_they_are_working_where_watched_and_are_silent_with_progress_false(capfd, monkeypatch):
    """The studies count no work: their line gives the time elapsed, and appears by default
    once a call has taken AUTO_SECONDS where someone watches."""
    seconds = []
    pendula.lyapunov("double", t_end=600, progress=seconds.append)
    assert len(seconds) >= 2 and seconds == sorted(seconds) and 0 <= seconds[0] < seconds[-1] < 60, seconds
    assert capfd.readouterr().err == ""
    monkeypatch.setattr(dense, "interactive", lambda stream=None: True)
    monkeypatch.setattr(dense, "AUTO_SECONDS", 0.1)
    pendula.lyapunov("double", t_end=600)
    err = capfd.readouterr().err
    assert "lyapunov double" in err and "elapsed" in err, err
    pendula.lyapunov("double", t_end=600, progress=False)
    assert capfd.readouterr() == ("", "")
    # A short call shows nothing by default.
    monkeypatch.setattr(dense, "AUTO_SECONDS", 3.0)
    pendula.divergence("double", t_end=5)
    assert capfd.readouterr().err == ""


def test_tqdm_bars_read_as_numbers_a_student_would_write(capfd):
    """With tqdm installed (pendula[progress]): a time bar gives the time run to 4 digits,
    a count bar whole counts."""
    pytest.importorskip("tqdm")
    bar = dense.Progress(0, 600, unit="s", desc="solve double")
    bar(84.6412345678)
    assert "84.64/600 s" in str(bar.bar), str(bar.bar)
    bar.close(600.0)
    back = dense.Progress(10, 0, unit="s")
    back(7.5)
    assert "2.5/10 s" in str(back.bar), str(back.bar)
    back.close(0.0)
    count = dense.Progress(0, 300, unit="members", label=None)
    count(13)
    assert "13/300" in str(count.bar) and "13.0" not in str(count.bar), str(count.bar)
    count.close(300)
