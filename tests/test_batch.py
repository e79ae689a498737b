"""pilots.batch: a stop signal that arrives while a worker pool forks (each case in a fresh
interpreter: an at-fork hook cannot be removed once registered)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

#: A stop handler like the command line's, and a hook that sends SIGTERM from inside the
#: parent's at-fork hooks: the moment a signal sent while `hesspipe run` starts a pool lands.
RACE = textwrap.dedent("""
    import os, signal, sys
    from hesspipe.pilots.batch import run_batch

    def stop(signum, frame):
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, stop)
    os.register_at_fork(after_in_parent=lambda: os.kill(os.getpid(), signal.SIGTERM))
    try:
        run_batch(abs, [-1, -2, -3, -4], workers=2, progress=False)
    except KeyboardInterrupt:
        sys.exit(3)
    sys.exit(0)
""")

#: Each worker sends SIGTERM to itself: it must die of it (the pool breaks), not hold it.
WORKER = textwrap.dedent("""
    import os, signal, sys
    from concurrent.futures.process import BrokenProcessPool
    from hesspipe.pilots.batch import run_batch

    def die(x):
        os.kill(os.getpid(), signal.SIGTERM)
        return x

    signal.signal(signal.SIGTERM, lambda s, f: None)   # the parent's own handler, inherited
    try:
        run_batch(die, [1, 2], workers=2, progress=False)
    except BrokenProcessPool:
        sys.exit(4)
    sys.exit(0)
""")


def _run(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)


def test_a_stop_sent_while_the_pool_forks_stops_the_batch_without_a_traceback():
    done = _run(RACE)
    # Before the fix: "Exception ignored in: <function <lambda>>", a traceback, and the batch
    # ran to its end (exit 0).
    assert done.returncode == 3, done.stderr
    assert "Traceback" not in done.stderr and "Exception ignored" not in done.stderr, done.stderr


def test_workers_release_the_held_stops_and_die_of_sigterm():
    done = _run(WORKER)
    assert done.returncode == 4, done.stderr
