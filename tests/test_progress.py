"""posekit.progress: bars that end finished (a loop stopped at a time budget ends full, not at 460/9000)."""

import io

from posekit.progress import finish, tqdm


def test_outside_jupyter_it_is_tqdm_and_finish_ends_the_bar_at_what_ran():
    out = io.StringIO()
    bar = tqdm(total=100, desc="budget", unit="step", file=out)
    bar.update(37)
    finish(bar)
    bar.close()
    assert bar.total == 37 and "100%" in out.getvalue() and "37/37" in out.getvalue()


def test_finish_leaves_a_full_bar_and_none_alone():
    bar = tqdm(range(3), file=io.StringIO())
    for _ in bar:
        pass
    finish(bar)
    finish(None)
    assert bar.total == 3 and bar.n == 3


def test_outside_a_terminal_the_bar_is_whole_lines_also_while_a_step_runs(monkeypatch):
    """Issue 45: in a log (not a terminal) a bar writes a line at the start, every LOG_SECONDS seconds even while one
    step runs long, and one at the end; never carriage returns."""
    import threading

    from posekit import progress

    monkeypatch.setattr(progress, "LOG_SECONDS", 0.4)
    out = io.StringIO()
    bar = tqdm(total=2, desc="train", unit="epoch", file=out)
    threading.Event().wait(2.2)  # one long step: the bar keeps saying it is alive
    bar.update(2)
    bar.close()
    lines = out.getvalue().splitlines()
    assert "\r" not in out.getvalue() and out.getvalue().endswith("\n")
    assert lines[0].startswith("train:   0%") and lines[-1].startswith("train: 100%") and "2/2" in lines[-1]
    assert sum("0/2" in ln for ln in lines) >= 2  # lines while the step ran, not only at its end
    assert len(set(lines)) == len(lines)  # no line twice
