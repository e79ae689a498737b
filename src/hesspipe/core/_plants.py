"""The plants file of SPEC.md (JSON): the two continuous-time plants a pilot loop is closed
around, and the cab's motion path. Re-exported by :mod:`hesspipe.core.formats`."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping

import control as ct
import numpy as np

from ._csv import decode
from ._tf import _read_tf, siso_coefficients, tf_coefficients
from .errors import HesspipeError
from .io import write_json


@dataclass(frozen=True)
class Plants:
    """The two continuous-time plants a pilot loop is closed around.

    Attributes
    ----------
    control_to_output : control.TransferFunction
        Yc: pilot control (aileron, normalised -1..1) → roll rate (rad/s).
    disturbance_to_output : control.TransferFunction
        Yd: lateral wind (ft/s) → roll rate (rad/s).
    meta : dict
        Extra keys of the JSON file (units, orders, fit, source...).
    motion_path : control.TransferFunction or None
        Controlled output → angular velocity (rad/s) the simulator cab imposes on the
        pilot, platform and motion filter included (SPEC.md "Data formats"). None: the
        paper's platform × washout acting on the output (a rate task). The vestibular
        part (canals, Km; otoliths) belongs to the pilot model, not to this path.
    """

    control_to_output: ct.TransferFunction
    disturbance_to_output: ct.TransferFunction
    meta: dict = field(default_factory=dict)
    motion_path: ct.TransferFunction | None = None

    def __post_init__(self):
        # Built in Python, each path is checked as a file's is (read_plants): continuous,
        # SISO, proper, finite; a (num, den) pair, a {"num", "den"} mapping, a state-space
        # or scipy system is taken as its transfer function.
        for key, excess in (("control_to_output", 0), ("disturbance_to_output", 0), ("motion_path", 1)):
            value = getattr(self, key)
            if value is None and key == "motion_path":
                continue
            checked = _read_tf(_as_coefficients(value, key), "Plants", key, excess=excess,
                               allow_zero=key != "control_to_output")
            if not isinstance(value, ct.TransferFunction):
                object.__setattr__(self, key, checked)

    @property
    def Yc(self) -> ct.TransferFunction:
        """``Yc``: the control-to-output transfer function (the paper's name)."""
        return self.control_to_output

    @property
    def Yd(self) -> ct.TransferFunction:
        """``Yd``: the disturbance-to-output transfer function (the paper's name)."""
        return self.disturbance_to_output


def as_plants(plants) -> Plants:
    """`plants` if it is a :class:`Plants`, else an error a researcher can act on.

    Parameters
    ----------
    plants : Plants

    Returns
    -------
    Plants
        `plants`, unchanged.

    Raises
    ------
    HesspipeError
        Naming ``plants`` and what was given (a path: :func:`read_plants` reads it).
    """
    if isinstance(plants, Plants):
        return plants
    hint = " (read_plants reads a plants file)" if isinstance(plants, (str, Path)) else (
        " (Plants(Yc, Yd) builds it from transfer functions)")
    raise HesspipeError(f"plants: expected a Plants{hint}, got {type(plants).__name__}")


def _as_coefficients(value, key: str) -> Mapping:
    """`value` (a transfer function in any form :class:`Plants` takes) as SPEC.md's
    ``{"num", "den", "dt"}``; anything else is refused naming `key`."""
    if isinstance(value, Mapping):
        return value
    if isinstance(value, (tuple, list)) and len(value) == 2:
        return {"num": np.atleast_1d(np.asarray(value[0], dtype=float)).tolist(),
                "den": np.atleast_1d(np.asarray(value[1], dtype=float)).tolist()}
    if hasattr(value, "to_tf") and not isinstance(value, ct.InputOutputSystem):   # scipy.signal.lti
        value = value.to_tf()
        return {"num": np.atleast_1d(value.num).tolist(), "den": np.atleast_1d(value.den).tolist(),
                "dt": getattr(value, "dt", None)}
    if isinstance(value, ct.StateSpace):
        value = ct.ss2tf(value)
    if isinstance(value, ct.TransferFunction):
        if value.ninputs != 1 or value.noutputs != 1:
            raise HesspipeError(f"Plants: field '{key}': expected a single-input single-output transfer "
                                f"function, got {value.noutputs} outputs x {value.ninputs} inputs")
        num, den = siso_coefficients(value)
        # python-control's dt: 0 or None continuous, True or a period discrete.
        return {"num": num.tolist(), "den": den.tolist(), "dt": None if not value.dt else value.dt}
    hint = " (a plants file: read_plants reads it)" if isinstance(value, (str, Path)) else ""
    raise HesspipeError(f"Plants: field '{key}': expected a transfer function (control.tf, a (num, den) "
                        f"pair or {{'num': [...], 'den': [...]}}), got {type(value).__name__}{hint}")


def read_plants(path: str | Path) -> Plants:
    """Read a plants JSON file (SPEC.md format) into :class:`Plants`.

    Parameters
    ----------
    path : path
        JSON with ``control_to_output`` and ``disturbance_to_output`` (continuous
        time, coefficients in descending powers of s); other keys are kept as
        :attr:`Plants.meta`.

    Returns
    -------
    Plants

    Raises
    ------
    HesspipeError
        Naming the file and the field: unreadable JSON, a missing or malformed
        transfer function, a discrete-time one (``dt`` other than 0 or null), one whose
        coefficients overflow when normalised, a zero ``control_to_output``.
    """
    path = Path(path)
    try:
        obj = json.loads(decode(path, "a plants JSON file")[0])
    except json.JSONDecodeError as exc:
        raise HesspipeError(f"{path}: not valid JSON ({exc})") from None
    if not isinstance(obj, Mapping):
        raise HesspipeError(f"{path}: expected a JSON object with 'control_to_output' and "
                            "'disturbance_to_output'")
    for key in ("control_to_output", "disturbance_to_output"):
        if key not in obj:
            raise HesspipeError(f"{path}: field '{key}' missing; expected "
                                "{\"num\": [...], \"den\": [...]}")
    tfs = ("control_to_output", "disturbance_to_output", "motion_path")
    meta = {k: v for k, v in obj.items() if k not in tfs}
    motion = obj.get("motion_path")
    # A zero Yc leaves the pilot nothing to control; a zero Yd (a target-only task) or motion
    # path (a fixed-base cab) is a plant of its own.
    return Plants(_read_tf(obj["control_to_output"], path, "control_to_output", allow_zero=False),
                  _read_tf(obj["disturbance_to_output"], path, "disturbance_to_output"), meta,
                  # The cab's rate of an angle display is s times the angle: a bare
                  # differentiator is a natural motion path (the pilot's loop stays proper).
                  None if motion is None else _read_tf(motion, path, "motion_path", excess=1))


def plants_coefficients(plants: Plants) -> dict:
    """The plants' transfer functions as SPEC.md's JSON writes them: the one record of a
    plants file's paths in every output that carries them.

    Parameters
    ----------
    plants : Plants
        Yc (control → output), Yd (disturbance → output) and the optional motion path
        (output → the cab's angular velocity).

    Returns
    -------
    dict
        ``control_to_output``, ``disturbance_to_output`` and, where given,
        ``motion_path``, each ``{"num": [...], "den": [...]}`` in descending powers of s.
    """
    obj = {"control_to_output": tf_coefficients(plants.control_to_output),
           "disturbance_to_output": tf_coefficients(plants.disturbance_to_output)}
    if plants.motion_path is not None:
        obj["motion_path"] = tf_coefficients(plants.motion_path)
    return obj


def write_plants(path: str | Path, plants: Plants, **extra) -> Path:
    """Write `plants` in the SPEC.md JSON format, atomically.

    Parameters
    ----------
    path : path
        The JSON file to write.
    plants : Plants
        Yc (control → output) and Yd (disturbance → output); its ``meta`` keys
        are written too.
    **extra
        Further top-level keys (units, orders, fit, source ...).

    Returns
    -------
    Path
        `path`.
    """
    obj = plants_coefficients(plants)
    obj.update(plants.meta)
    obj.update(extra)
    return write_json(path, obj)
