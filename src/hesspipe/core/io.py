"""Atomic file output and hesspipe's output folders.

Every file hesspipe writes goes through these helpers: content is written to
a temporary file in the destination folder and renamed into place, so an
interrupted or failed run never leaves a half-written file. A stage that
writes several files uses :func:`staged_output`, which publishes all of them
only when the stage succeeds.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any, Iterator

from . import stops
from .errors import HesspipeError

#: Name prefixes of the temporary files and folders hesspipe makes beside its outputs; with
#: the process id after them they are recognisably hesspipe's, so a later run can remove
#: those a killed run left (and nothing else).
TMP_PREFIX = ".hesspipe-tmp-"
STAGING_PREFIX = ".hesspipe-staging-"

#: The file that marks a folder as a hesspipe output and lists the files hesspipe owns in it.
MARKER = ".hesspipe-output"

# Errors of the file system that mean "you cannot write there", not a bug.
_WRITE_ERRORS = {errno.EACCES, errno.EPERM, errno.EROFS, errno.ENOSPC, errno.EDQUOT, errno.EISDIR,
                 errno.ENOTDIR, errno.EEXIST, errno.EFBIG, errno.ENAMETOOLONG}


def read_bytes(path: str | os.PathLike, what: str) -> bytes:
    """The bytes of an input file, or a one-line error naming it and what it should be.

    Parameters
    ----------
    path : path
        The file.
    what : str
        What it should be, for messages ("a TOML file", "a measured-run CSV").

    Raises
    ------
    HesspipeError
        Missing, a folder, or unreadable.
    """
    path = Path(path)
    check_published(path)
    try:
        return path.read_bytes()
    except FileNotFoundError:
        raise HesspipeError(f"{path}: file not found; expected {what}") from None
    except IsADirectoryError:
        raise HesspipeError(f"{path}: is a folder, expected {what}") from None
    except OSError as exc:
        raise HesspipeError(f"{path}: cannot be read ({exc.strerror or exc}); expected {what}") from None


def check_published(path: str | os.PathLike) -> None:
    """Raise if `path` lies in a hesspipe output folder whose publication never finished.

    A command killed while it moved its files into place (SIGKILL, a power cut: Ctrl-C and
    SIGTERM wait for the move) leaves the folder's files of two runs side by side; the
    folder's marker says so until a run publishes it whole.

    Parameters
    ----------
    path : str or PathLike
        An input file.

    Raises
    ------
    HesspipeError
        Naming the file and what to do.
    """
    path = Path(path)
    # Every folder above it: a stage's files lie in sub-folders of the one it publishes, which
    # may hold a marker of their own (a cohort's runs in pilots/cohort/). Resolved, so that a
    # path through `..` is judged by where the file is.
    for folder in path.resolve().parents:
        marker = _stopped(folder)
        if marker is not None:
            raise HesspipeError(f"{path}: {folder} holds a hesspipe {marker['hesspipe_output']} output whose "
                                f"writing was stopped midway (its {MARKER} file says so; its files may come "
                                "from two runs); expected a complete output: run the command that wrote it "
                                "again")


def _cannot_write(path, exc: OSError) -> HesspipeError:
    return HesspipeError(f"{path}: cannot write ({exc.strerror or exc}); choose a location you can "
                         "write to")


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside `path`; rename it onto `path` on success.

    The temporary file keeps the suffix of `path` so libraries that pick a
    format from the extension (matplotlib, pandas) still work. A file system
    that refuses the write (permission, read-only, full) raises
    :class:`~hesspipe.core.errors.HesspipeError` naming `path`.

    Parameters
    ----------
    path : str or PathLike
        The final file; its folder is created if needed.
    """
    path = Path(path)
    # A write of this very file that was killed left its temporary file beside it (at best:
    # a folder one may write to but not list keeps it).
    with contextlib.suppress(OSError):
        remove_leftovers(path.parent, only=f"-{path.name}")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f"{TMP_PREFIX}{os.getpid()}-", suffix=f"-{path.name}",
                                   dir=path.parent)
    except OSError as exc:
        base = _existing_ancestor(path.parent)
        if not base.is_dir():
            raise HesspipeError(f"{path}: cannot create it: {base} is a file, not a folder") from None
        raise _cannot_write(path, exc) from None
    os.close(fd)
    tmp = Path(tmp)
    try:
        try:
            yield tmp
            # mkstemp makes the file 0600; give it the permissions a plain open() would.
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o666 & ~umask)
            os.replace(tmp, path)
        except OSError as exc:
            if exc.errno in _WRITE_ERRORS:
                raise _cannot_write(path, exc) from None
            raise
    finally:
        if tmp.exists():
            tmp.unlink()


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write `text` to `path` atomically (UTF-8) and return the path.

    Parameters
    ----------
    path : str or PathLike
        The file (replaced atomically if it exists).
    text : str
        Its content.
    """
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def _json_default(obj: Any):
    import numpy as np  # here, not at import: the command line starts without numpy

    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    if isinstance(obj, complex):
        return {"re": obj.real, "im": obj.imag}
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def to_json(obj: Any) -> str:
    """Serialise `obj` (numpy scalars and arrays allowed) as indented JSON.

    Non-finite floats are written as ``null``: JSON has no NaN.

    Parameters
    ----------
    obj : object
        Dicts, lists, numbers, strings, numpy scalars and arrays, Paths.
    """
    import numpy as np  # here, not at import: the command line starts without numpy

    def finite(obj: Any) -> Any:
        if isinstance(obj, (float, np.floating)):
            return float(obj) if np.isfinite(obj) else None
        if isinstance(obj, dict):
            return {str(k): finite(v) for k, v in obj.items()}
        if isinstance(obj, (list, tuple)):
            return [finite(v) for v in obj]
        if isinstance(obj, np.ndarray):
            return finite(obj.tolist())
        return obj

    return json.dumps(finite(obj), indent=2, default=_json_default, allow_nan=False) + "\n"


def write_json(path: str | os.PathLike, obj: Any) -> Path:
    """Write `obj` as JSON to `path` atomically and return the path.

    Parameters
    ----------
    path : str or PathLike
        The file (replaced atomically if it exists).
    obj : object
        What :func:`to_json` accepts.
    """
    return write_text(path, to_json(obj))



# -- output folders: recognised, checked before computing, published whole -------------------
#
# A folder is hesspipe's when it holds MARKER, a JSON object naming the kind of output
# ("flight", "plants", "cohort", "run", ...) and the files hesspipe published there. Folders
# written before markers existed are recognised by their manifest.json naming its stage. The
# tool writes only into a new folder, an empty one, or one of its own of the same kind; it
# replaces and deletes only files its marker lists and temporary files named with its prefix.


def _read_json(path: Path):
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def _safe_rel(rel) -> bool:
    return isinstance(rel, str) and bool(rel) and not Path(rel).is_absolute() and ".." not in Path(rel).parts


def _read_marker(folder: Path) -> dict | None:
    data = _read_json(folder / MARKER)
    if (not isinstance(data, dict) or not isinstance(data.get("hesspipe_output"), str)
            or not isinstance(data.get("files"), list)):
        return None
    return data


def _legacy_manifest(folder: Path) -> tuple[str, set[str]] | None:
    """(kind, owned files) of a folder an older hesspipe wrote (no marker), from its manifest."""
    data = _read_json(folder / "manifest.json")
    if isinstance(data, dict) and isinstance(data.get("stage"), str):
        listed = data.get("outputs") if isinstance(data.get("outputs"), dict) else {}
        files = data.get("files") if isinstance(data.get("files"), list) else []
        return data["stage"], {r for r in {"manifest.json", *listed, *files} if _safe_rel(r)}
    # A pipeline run's root: stage folders whose manifests name them; the report stage
    # publishes into the root, its manifest lists what it wrote there.
    for sub in sorted(p for p in folder.iterdir() if p.is_dir()) if folder.is_dir() else []:
        data = _read_json(sub / "manifest.json")
        if isinstance(data, dict) and data.get("stage") == sub.name:
            report = _read_json(folder / "report" / "manifest.json")
            listed = report.get("outputs") if isinstance(report, dict) else None
            owned = {"report/manifest.json", *(listed if isinstance(listed, dict) else ["report.md"])}
            return "run", {r for r in owned if _safe_rel(r)}
    return None


def output_kind(folder: str | os.PathLike) -> str | None:
    """The kind of hesspipe output `folder` holds, or None if it is not hesspipe's.

    Parameters
    ----------
    folder : str or PathLike
        The folder to look at (its marker file).
    """
    folder = Path(folder)
    marker = _read_marker(folder)
    if marker is not None:
        return marker["hesspipe_output"]
    legacy = _legacy_manifest(folder)
    return legacy[0] if legacy else None


def output_publishing(folder: str | os.PathLike) -> bool:
    """Whether `folder`'s marker says its publication was stopped midway.

    Parameters
    ----------
    folder : str or PathLike
        A hesspipe output folder.
    """
    return _stopped(Path(folder)) is not None


def _stopped(folder: Path) -> dict | None:
    """`folder`'s marker where it says its publication was stopped midway, else None."""
    marker = _read_marker(folder)
    return marker if marker is not None and marker.get("publishing") else None


def _owned(folder: Path) -> set[str]:
    marker = _read_marker(folder)
    if marker is not None:
        return {r for r in marker["files"] if _safe_rel(r)}
    legacy = _legacy_manifest(folder)
    return legacy[1] if legacy else set()


def _ours(entry: Path) -> bool:
    """True for a temporary file or staging folder hesspipe made (see TMP_PREFIX)."""
    return entry.name.startswith((TMP_PREFIX, STAGING_PREFIX)) or entry.name == MARKER


def _pid_of(entry: Path, prefixes=(TMP_PREFIX, STAGING_PREFIX)) -> int | None:
    rest = entry.name
    for prefix in prefixes:
        rest = rest.removeprefix(prefix)
    head = rest.split("-", 1)[0]
    return int(head) if head.isdigit() else None


def _alive(pid: int) -> bool:
    if os.name == "nt":
        # os.kill(pid, 0) sends a console Ctrl-C to a process group there, and getting a
        # process's state needs the Win32 API: every leftover is kept (nothing lost).
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process: alive
        return True
    return True


def remove_leftovers(folder: str | os.PathLike, *, only: str | None = None,
                     prefix: str | None = None) -> list[Path]:
    """Remove the temporary files and staging folders a killed hesspipe run left in `folder`.

    Only entries named with hesspipe's prefixes whose process is gone are removed;
    a user's own hidden files are never touched. Returns what was removed.

    Parameters
    ----------
    folder : str or PathLike
        The output folder to clean (nothing happens if it does not exist).
    only : str, optional
        Only temporary files whose name ends so (those of one file's writes).
    prefix : str, optional
        Only entries named with this prefix of hesspipe's and a process id (a folder of
        hesspipe's own outside an output folder, in the system's temporary folder).
    """
    folder = Path(folder)
    removed = []
    if not folder.is_dir():
        return removed
    prefixes = (TMP_PREFIX, STAGING_PREFIX) if prefix is None else (prefix,)
    for entry in folder.iterdir():
        if not entry.name.startswith(prefixes):
            continue
        if only is not None and not (entry.name.startswith(TMP_PREFIX) and entry.name.endswith(only)):
            continue
        pid = _pid_of(entry, prefixes)
        if pid is None or _alive(pid):
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry, ignore_errors=True)
        else:
            entry.unlink(missing_ok=True)
        removed.append(entry)
    return removed


def _probe(folder: Path, target: Path) -> None:
    """Raise unless a file can be created in the existing `folder` (for output `target`)."""
    try:
        fd, name = tempfile.mkstemp(prefix=f"{TMP_PREFIX}{os.getpid()}-probe-", dir=folder)
        os.close(fd)
        os.unlink(name)
    except OSError as exc:
        raise _cannot_write(target, exc) from None


def _existing_ancestor(path: Path) -> Path:
    for parent in [path, *path.parents]:
        if parent.exists():
            return parent
    return Path(".")


def check_output_dir(path: str | os.PathLike, kind: str, *, write: bool = True) -> Path:
    """Raise :class:`~hesspipe.core.errors.HesspipeError` unless `path` may receive `kind` output.

    Accepted: a folder that does not exist yet (inside a folder that is writable), an empty
    folder, or a folder hesspipe wrote with output of the same `kind`. Refused, in one line
    saying why and what to do: a file, a non-empty folder that is not hesspipe's, another
    kind of hesspipe output, and (with `write`) a location that cannot be written to. Call
    it before computing, so no result is lost to a failed write.

    Parameters
    ----------
    path : str or PathLike
        The output folder.
    kind : str
        The kind of output, e.g. ``"flight"`` or ``"plants"`` (what the marker records).
    write : bool
        Also check that the location can be written to.

    Returns
    -------
    Path
        `path`.
    """
    path = Path(path)
    if path.is_dir():
        found = output_kind(path)
        if found is None and any(not _ours(e) for e in path.iterdir()):
            raise HesspipeError(f"{path}: folder is not empty and was not written by hesspipe (no "
                                f"{MARKER} file); hesspipe writes only into a new or empty folder or one "
                                "it wrote: choose another folder")
        if found is not None and found != kind:
            raise HesspipeError(f"{path}: holds hesspipe's {found} output; choose another folder for "
                                f"the {kind} output")
        if write:
            _probe(path, path)
        return path
    if path.exists() or path.is_symlink():
        raise HesspipeError(f"{path}: exists and is not a folder; expected an output folder")
    base = _existing_ancestor(path.parent)
    if not base.is_dir():
        raise HesspipeError(f"{path}: cannot create this folder: {base} is a file, not a folder")
    if write:
        _probe(base, path)
    return path


def check_output_file(path: str | os.PathLike) -> Path:
    """Raise unless the file `path` can be written (checked before computing).

    `path` may exist (a file the user named is replaced, atomically); it must not be
    a folder, and the folder it goes in must exist or be creatable, and be writable.

    Parameters
    ----------
    path : str or PathLike
        The file to be written.

    Returns
    -------
    Path
        `path`.
    """
    path = Path(path)
    if path.is_dir():
        raise HesspipeError(f"{path}: is a folder; expected a file name")
    if path.exists() and not path.is_file():
        raise HesspipeError(f"{path}: exists and is not a regular file; expected a file name")
    base = _existing_ancestor(path.parent)
    if not base.is_dir():
        raise HesspipeError(f"{path}: cannot create it: {base} is a file, not a folder")
    _probe(base, path)
    return path


def _write_marker(folder: Path, kind: str, files, *, publishing: bool = False) -> None:
    write_json(folder / MARKER, {
        "hesspipe_output": kind,
        "note": "written by hesspipe: this folder is its output; the files listed are replaced "
                "or removed when it publishes again, nothing else is",
        **({"publishing": True} if publishing else {}),
        "files": sorted(files)})


@contextlib.contextmanager
def _signals_held() -> Iterator[None]:
    """Hold Ctrl-C and SIGTERM until the block ends, then act on them as they would have.

    A publication moves its files one at a time; stopped between two moves the folder would
    hold two runs' files. The moves take milliseconds, so the signal waits for them. (SIGKILL
    cannot wait: the marker's ``publishing`` says what it left, :func:`check_published`.)
    """
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    held: list[int] = []
    previous = {sig: signal.signal(sig, lambda signum, frame: held.append(signum))
                for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        stops.restore(previous)
        for sig in dict.fromkeys(held):
            signal.raise_signal(sig)


def mark_output_dir(path: str | os.PathLike, kind: str) -> Path:
    """Create `path` (checked with :func:`check_output_dir`) and mark it as `kind` output.

    Parameters
    ----------
    path : str or PathLike
        The output folder.
    kind : str
        The kind of output it holds.

    Returns
    -------
    Path
        `path`, existing and marked.
    """
    path = check_output_dir(path, kind)
    path.mkdir(parents=True, exist_ok=True)
    if _read_marker(path) is None:
        _write_marker(path, kind, _owned(path))
    return path


def _publish(stage: Path, out_dir: Path, kind: str) -> None:
    """Move every file of `stage` into `out_dir`; remove the files hesspipe owned there before
    that this publication does not hold (a folder is published whole, never merged)."""
    # A nested writer's marker in the staging root is replaced by ours.
    (stage / MARKER).unlink(missing_ok=True)
    # The manifest goes last: its presence is what marks a stage complete.
    files = sorted((str(p.relative_to(stage)) for p in stage.rglob("*") if p.is_file()),
                   key=lambda r: (Path(r).name == "manifest.json", r))
    owned = _owned(out_dir)
    for rel in files:
        dst = out_dir / rel
        clash = [q for q in dst.parents if q != out_dir and q.is_relative_to(out_dir)
                 and (q.exists() or q.is_symlink()) and not q.is_dir()]
        if (dst.exists() or dst.is_symlink()) and (dst.is_dir() or rel not in owned):
            clash.append(dst)
        if clash:
            raise HesspipeError(f"{clash[0]}: exists and was not written by hesspipe; move it away "
                                "or choose another output folder")
    try:
        # Marker first: from here on every file this publication may leave is listed, and
        # the folder says it is being written until the last marker.
        _write_marker(out_dir, kind, owned | set(files), publishing=True)
        for rel in files:
            dst = out_dir / rel
            dst.parent.mkdir(parents=True, exist_ok=True)
            os.replace(stage / rel, dst)
        for rel in sorted(owned - set(files)):
            gone = out_dir / rel
            if gone.is_file() or gone.is_symlink():
                gone.unlink()
            for parent in gone.parents:  # sub-folders this removal emptied
                if parent == out_dir or not parent.is_dir() or any(parent.iterdir()):
                    break
                parent.rmdir()
        _write_marker(out_dir, kind, files)
    except OSError as exc:
        raise _cannot_write(out_dir, exc) from None


@contextlib.contextmanager
def staged_output(out_dir: str | os.PathLike, kind: str = "output") -> Iterator[Path]:
    """Collect a stage's files in a hidden folder and publish them together.

    `out_dir` is checked first (:func:`check_output_dir`: new, empty or hesspipe's own
    `kind` output, writable), before the caller computes anything. Yields a temporary
    folder inside `out_dir`. When the block succeeds every file in it is renamed into
    `out_dir` (sub-folders included) and the files of an earlier publication that this
    one does not hold are removed; when it raises, the temporary folder is removed and
    `out_dir` is left as it was (and removed again if this call created it).

    Parameters
    ----------
    out_dir : str or PathLike
        The output folder.
    kind : str
        The kind of output (what the marker records).
    """
    out_dir = check_output_dir(out_dir, kind)
    remove_leftovers(out_dir)
    created = not out_dir.exists()
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        stage = Path(tempfile.mkdtemp(prefix=f"{STAGING_PREFIX}{os.getpid()}-", dir=out_dir))
    except OSError as exc:
        raise _cannot_write(out_dir, exc) from None
    try:
        yield stage
        stops.act()   # a stop whose exception was swallowed (core.stops) publishes nothing
        with _signals_held():
            _publish(stage, out_dir, kind)
    finally:
        shutil.rmtree(stage, ignore_errors=True)
        if created and out_dir.exists() and not any(out_dir.iterdir()):
            out_dir.rmdir()
