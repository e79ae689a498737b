"""Transfer functions as SPEC.md's JSON holds them: coefficients in descending powers of s
(private; :mod:`hesspipe.core.formats` re-exports them)."""

from __future__ import annotations

import math
from typing import Mapping

import control as ct
import numpy as np

from .errors import HesspipeError


def siso_coefficients(sys) -> tuple[np.ndarray, np.ndarray]:
    """Numerator and denominator of a SISO transfer function as 1-D float arrays.

    The one place that reaches into python-control's nested ``num[0][0]``.

    Parameters
    ----------
    sys : control.TransferFunction
        Single-input single-output, continuous or discrete.

    Returns
    -------
    num, den : ndarray
        Coefficients in descending powers of s (or z), at least one each, as
        stored (not normalised; leading zeros kept).
    """
    num = np.atleast_1d(np.squeeze(sys.num[0][0])).astype(float)
    den = np.atleast_1d(np.squeeze(sys.den[0][0])).astype(float)
    return num, den


def tf_coefficients(sys: ct.TransferFunction) -> dict:
    """Return ``{"num": [...], "den": [...]}`` of a SISO continuous transfer function.

    Parameters
    ----------
    sys : control.TransferFunction
        Single-input single-output.

    Returns
    -------
    dict
        Lists of floats, descending powers of s (see :func:`siso_coefficients`).
    """
    num, den = siso_coefficients(sys)
    return {"num": num.tolist(), "den": den.tolist()}


def _read_tf(obj, path, key, *, excess: int = 0, allow_zero: bool = True) -> ct.TransferFunction:
    if not isinstance(obj, Mapping):
        raise HesspipeError(f"{path}: field '{key}': expected an object with 'num' and 'den', got {obj!r}")
    dt = obj.get("dt")
    # python-control's convention: dt None or 0 is continuous time; anything else is a
    # sampled system whose coefficients mean powers of z, not s.
    if dt is not None and not (isinstance(dt, (int, float)) and not isinstance(dt, bool) and dt == 0):
        raise HesspipeError(f"{path}: field '{key}.dt': {dt!r} makes it a discrete-time transfer "
                            "function; expected continuous time (dt null or 0, or no dt): convert "
                            "it to continuous time first")
    coeffs = {}
    for part in ("num", "den"):
        value = obj.get(part)
        if (not isinstance(value, list) or not value
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                           and math.isfinite(v) for v in value)):
            raise HesspipeError(f"{path}: field '{key}.{part}': expected a non-empty list of finite "
                                f"numbers (descending powers of s), got {value!r}")
        coeffs[part] = np.trim_zeros(np.asarray(value, dtype=float), "f")
    num, den = coeffs["num"], coeffs["den"]
    if den.size == 0:
        raise HesspipeError(f"{path}: field '{key}.den': expected a non-zero polynomial")
    if num.size == 0:
        if not allow_zero:
            raise HesspipeError(f"{path}: field '{key}.num': expected a non-zero polynomial")
        num = np.zeros(1)
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        scaled = np.concatenate([num, den]) / den[0]
    if not np.isfinite(scaled).all():
        raise HesspipeError(f"{path}: field '{key}': its coefficients divided by the denominator's leading one "
                            f"({den[0]:g}) overflow; expected a gain and poles that are finite numbers")
    if num.size > den.size + excess:
        what = ("a proper transfer function" if not excess else
                f"a numerator degree at most {excess} above the denominator's (s: the rate of an angle)")
        raise HesspipeError(f"{path}: field '{key}': not proper (numerator degree {num.size - 1} "
                            f"> denominator degree {den.size - 1}); expected {what}")
    return ct.tf(num, den)
