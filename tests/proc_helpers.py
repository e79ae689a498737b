"""Process helpers of the tests: descendants of a process, liveness, and a child that
cannot write where permission bits say it may not (also as root)."""

from __future__ import annotations

import os
from pathlib import Path


def drop_write_override() -> None:
    """Drop CAP_DAC_OVERRIDE from this (forked, root) process: it stays root and reads
    everything root owns, but permission bits now stop its writes, as for any user."""
    import ctypes

    class Header(ctypes.Structure):
        _fields_ = [("version", ctypes.c_uint32), ("pid", ctypes.c_int)]

    class Data(ctypes.Structure):
        _fields_ = [("effective", ctypes.c_uint32), ("permitted", ctypes.c_uint32),
                    ("inheritable", ctypes.c_uint32)]

    libc = ctypes.CDLL(None, use_errno=True)
    header, data = Header(0x20080522, 0), (Data * 2)()  # _LINUX_CAPABILITY_VERSION_3
    if libc.capget(ctypes.byref(header), data) != 0:
        raise OSError(ctypes.get_errno(), "capget failed")
    cap_dac_override = 1 << 1
    data[0].effective &= ~cap_dac_override & 0xFFFFFFFF
    data[0].permitted &= ~cap_dac_override & 0xFFFFFFFF
    if libc.capset(ctypes.byref(header), data) != 0:
        raise OSError(ctypes.get_errno(), "capset failed")


def descendants(pid: int) -> set[int]:
    """Every live descendant of `pid` (from /proc)."""
    parent = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if fields[0] != "Z":
                parent[int(entry.name)] = int(fields[1])
    found, frontier = set(), {pid}
    while frontier:
        frontier = {c for c, p in parent.items() if p in frontier} - found
        found |= frontier
    return found


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def sigterm_when_ready(argv: list[str], err_file: Path, ready, *, timeout_s: float = 60.0,
                       settle_s: float = 0.0, sig=None) -> tuple[int, list[int]]:
    """Run `argv`, send SIGTERM (or `sig`) once ``ready(workers, stderr_text)`` holds; (exit
    code, orphans).

    stderr goes to `err_file` (a file, not a pipe: orphans must not block the test). Orphans
    are the worker processes still alive 5 s after the command exited; whatever this call
    started is killed before it returns, so a failing test leaves nothing behind.
    """
    import signal
    import subprocess
    import time

    workers: set[int] = set()
    with open(err_file, "w") as err_fh:
        proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=err_fh)
    try:
        deadline = time.monotonic() + timeout_s
        while not ready(workers, err_file.read_text()):
            assert proc.poll() is None, err_file.read_text()
            assert time.monotonic() < deadline, "the worker processes did not appear"
            time.sleep(0.05)
            workers = descendants(proc.pid)
        if settle_s:
            time.sleep(settle_s)
            workers = descendants(proc.pid)
        proc.send_signal(signal.SIGTERM if sig is None else sig)
        code = proc.wait(timeout=30)
        deadline = time.monotonic() + 5
        while any(alive(p) for p in workers) and time.monotonic() < deadline:
            time.sleep(0.05)
        orphans = [p for p in workers if alive(p)]
    finally:
        if proc.poll() is None:
            proc.kill()
        for pid in workers:  # only the processes this call started
            if alive(pid):
                os.kill(pid, signal.SIGKILL)
    return code, orphans
