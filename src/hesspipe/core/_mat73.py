"""MATLAB version 7.3 files: HDF5 in MATLAB's layout, read as scipy reads the older versions.

``save -v7.3`` (MATLAB's choice for variables over 2 GB, and many laboratories' default)
writes an HDF5 file behind a 512-byte MATLAB header, which ``scipy.io.loadmat`` does not
read. h5py reads the HDF5; this module undoes MATLAB's layout so that
:func:`hesspipe.core._mat.mat_frame` sees what ``loadmat(..., squeeze_me=True,
simplify_cells=True)`` gives for a version 7 file:

- a numeric array is stored transposed (MATLAB is column-major): read back in MATLAB's
  shape, ``x`` of 8192 x 5 as 8192 x 5;
- ``char`` arrays are UTF-16 code units: a string;
- a struct is a group, its fields its members: a dict;
- a struct array is a group whose fields are arrays of references, one per element (in
  MATLAB's column-major order): a list of dicts; a cell array is an array of references:
  a list (of numbers only: the matrix they make, as scipy's objects are read);
- a logical is its 0s and 1s, as scipy reads it; empty arrays (``MATLAB_empty``), complex
  numbers, function handles and objects (``string``, ``table``, ``timeseries``) are no
  signal and are left out (None).
"""

from __future__ import annotations

import io as _io

import numpy as np

from .errors import HesspipeError, reason

#: MATLAB classes read as numbers (a logical as 0 and 1, as scipy reads it from version 7).
_NUMERIC = frozenset({"double", "single", "int8", "uint8", "int16", "uint16", "int32", "uint32",
                      "int64", "uint64", "logical"})


def hdf5_content(raw: bytes, path) -> dict:
    """The variables of a version 7.3 MAT file, as ``loadmat(simplify_cells=True)`` gives them.

    Parameters
    ----------
    raw : bytes
        The file's content.
    path : path
        The file (for messages).

    Returns
    -------
    dict
        Variable name → ndarray (MATLAB's shape), str, dict (a struct), list (a struct or
        cell array) or None (not a signal); ``__header__`` → the MATLAB header line (bytes).

    Raises
    ------
    HesspipeError
        Naming the file when its HDF5 cannot be read.
    """
    import h5py  # deferred: only version 7.3 files need it

    try:
        h5 = h5py.File(_io.BytesIO(raw), "r")
    except OSError as exc:
        raise HesspipeError(f"{path}: not a readable MATLAB 7.3 (HDF5) file ({reason(exc)})") \
            from None
    with h5:
        content = {"__header__": raw[:116].rstrip(b" \x00")}
        for name, item in h5.items():
            if not name.startswith("#"):   # #refs#, #subsystem#: MATLAB's own storage
                content[name] = _value(h5, item)
    return content


def _class(item) -> str:
    """MATLAB's class of an HDF5 item ('' when it states none)."""
    value = item.attrs.get("MATLAB_class", b"")
    return value.decode("ascii", "replace") if isinstance(value, bytes) else str(value)


def _value(h5, item):
    """`item` (a dataset or group) as scipy's simplified cells give it."""
    import h5py

    cls = _class(item)
    if isinstance(item, h5py.Group):
        if cls != "struct":
            return None
        fields = {key: item[key] for key in item}
        refs = [f for f in fields.values() if isinstance(f, h5py.Dataset) and not _class(f)
                and f.dtype == h5py.ref_dtype]
        if fields and len(refs) == len(fields):
            # A struct array: each field holds one reference per element.
            cells = {key: np.asarray(f[()]).T.ravel(order="F") for key, f in fields.items()}
            n = min(c.size for c in cells.values())
            return [{key: _value(h5, h5[c[i]]) for key, c in cells.items()} for i in range(n)]
        return {key: _value(h5, f) for key, f in fields.items()}
    if item.attrs.get("MATLAB_empty", 0) or "MATLAB_object_decode" in item.attrs:
        return None
    if cls == "cell":
        refs = np.asarray(item[()]).T
        cells = [_value(h5, h5[ref]) for ref in refs.ravel(order="F")]
        if cells and all(isinstance(c, float) for c in cells):   # a cell of numbers: a matrix, as scipy's
            return np.array(cells).reshape(refs.shape, order="F")
        return cells
    if cls == "char":
        codes = np.asarray(item[()]).T.ravel(order="F")
        return "".join(chr(int(c)) for c in codes)
    if cls not in _NUMERIC or item.dtype.kind not in "iuf":
        return None   # complex (a compound of real and imag), function handles
    a = np.asarray(item[()]).T
    return float(a.ravel()[0]) if a.size == 1 else a
