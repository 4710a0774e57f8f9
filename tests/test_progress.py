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
