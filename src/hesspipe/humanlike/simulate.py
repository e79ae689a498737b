"""Fine-step, block-by-block time-domain simulation of a pilot-vehicle loop.

Each linear block (pilot equaliser and neuromuscular system, proprioceptive
feedback, motion path, canals, remnant filter, actuator, plant) is its own
state space discretised exactly with a zero-order hold at the fine step h;
the blocks exchange signals once per step. The visual delay is an exact
sample buffer of round(tau/h) steps, the rate limit acts on the actuator
output step by step. Signals are logged by sampling the fine-step signals.

Speed: a loop of ~70k steps over a dozen small blocks is too slow as
interpreted numpy calls (~2 s a run), so the loop for a given wiring is
written out as straight-line Python over scalar floats and compiled once;
the block matrices appear in it as exact float literals (``repr``).
"""

from __future__ import annotations

from dataclasses import dataclass

from .lti import Discrete


@dataclass(frozen=True)
class Wiring:
    """Everything the stepper needs, already discretised at step `h` (s).

    Blocks are :class:`~hesspipe.humanlike.lti.Discrete`; `plant` has two
    inputs (plant input, side wind). `pilot` is ``"precision"`` (block
    ``eqnm`` driven by the delayed error and, with motion, ``vnm``: canals, motion
    path and neuromuscular system driven by the output delayed by the vestibular
    delay) or ``"hess"`` (blocks ``nm``, ``pf`` and, with motion, ``motion`` and ``scc``).

    Attributes
    ----------
    h : float
        Fine step, s.
    delay_steps : int
        Visual delay buffer, fine steps.
    pilot : {"precision", "hess"}
    blocks : dict
        Discretised blocks by name.
    Ke, Km : float
        Visual and vestibular gains.
    motion_delay_steps : int
        Vestibular delay, fine steps.
    remnant_at : {"control", "error"}
        Where the remnant enters.
    rate_limit : float or None
        Actuator rate limit, control units/s.
    disturbance : {"input", "wind"}
        Where the disturbance enters.
    gain_drift : bool
        The visual path's gain is multiplied by a per-step factor (``kv``, the pilot's
        within-run gain variation); off, the stepper is the time-invariant one.
    threshold : float or None
        Indifference threshold on the perceived error, output units: a dead zone of this
        half-width before the visual path (errors inside it draw no response); None: none.
    ff_delay_steps : int or None
        Delay of the target into block ``ffnm``, fine steps (0: none); None: the visual
        delay's buffer, shared with the error.

    A precision pilot on a pursuit display has block ``ffnm`` too: the feedforward path on
    the target, delayed by ``ff_delay_steps``.
    """

    h: float
    delay_steps: int
    pilot: str
    blocks: dict
    Ke: float = 0.0
    Km: float = 0.0
    motion_delay_steps: int = 0
    remnant_at: str = "control"
    rate_limit: float | None = None
    disturbance: str = "input"
    gain_drift: bool = False
    threshold: float | None = None
    ff_delay_steps: int | None = None


def delay_steps(tau: float, h: float, holds: int) -> int:
    """Buffer length (fine steps) that realises a loop delay `tau` (s).

    Every zero-order hold between blocks on the outer loop (pilot input,
    actuator input, plant input: `holds` of them) adds on average half a step
    of lag; the buffer is shortened by that, so the loop's total delay is
    ``(steps + holds/2) h`` (the value the truth reports).

    Parameters
    ----------
    tau : float
        Delay, s.
    h : float
        Fine step, s.
    holds : int
        Zero-order holds on the outer loop.
    """
    return max(1, int(round(tau / h - holds / 2.0)))


def _lit(x: float) -> str:
    return repr(float(x))


def _output(name: str, blk: Discrete, inputs: list[str]) -> str:
    terms = [f"{_lit(c)}*{name}{i}" for i, c in enumerate(blk.C) if c != 0.0]
    terms += [f"{_lit(dj)}*{u}" for dj, u in zip(blk.D, inputs) if dj != 0.0]
    return " + ".join(terms) if terms else "0.0"


def _update(name: str, blk: Discrete, inputs: list[str]) -> list[str]:
    n = blk.Ad.shape[0]
    lines = []
    for i in range(n):
        terms = [f"{_lit(a)}*{name}{j}" for j, a in enumerate(blk.Ad[i]) if a != 0.0]
        terms += [f"{_lit(b)}*{u}" for b, u in zip(blk.Bd[i], inputs) if b != 0.0]
        lines.append(f"t_{name}{i} = " + (" + ".join(terms) if terms else "0.0"))
    lines += [f"{name}{i} = t_{name}{i}" for i in range(n)]
    return lines


def _source(wr: Wiring) -> str:
    b = wr.blocks
    hess = wr.pilot == "hess"
    motion = hess and "motion" in b
    init = [f"{name}{i} = 0.0" for name, blk in b.items() if blk is not None
            for i in range(blk.Ad.shape[0])]
    body = ["wk = w[k]", "rk = r[k]", "dk = d[k]",
            f"n = g*({_output('rem', b['rem'], ['wk'])})"]
    pilot_block = "nm" if hess else "eqnm"
    body.append(f"delta = {_output(pilot_block, b[pilot_block], ['0.0'])}")
    vestibular = not hess and b.get("vnm") is not None
    feedforward = not hess and b.get("ffnm") is not None
    own_ff = feedforward and wr.ff_delay_steps is not None
    if feedforward:
        # Strictly proper like the vestibular block: its state alone gives its output.
        body.append(f"delta = delta + ({_output('ffnm', b['ffnm'], ['0.0'])})")
    if vestibular:
        # Strictly proper: its output is its state's, so the current y is not needed yet.
        body.append(f"delta = delta - {_lit(wr.Km)}*({_output('vnm', b['vnm'], ['0.0'])})")
    body.append("u = delta + n" if wr.remnant_at == "control" else "u = delta")
    body.append(f"a = {_output('act', b['act'], ['u'])}" if b.get("act") is not None else "a = u")
    if wr.rate_limit is not None:
        step = _lit(wr.rate_limit * wr.h)
        body += ["da = a - rlp", f"if da > {step}: da = {step}",
                 f"elif da < -{step}: da = -{step}", "a = rlp + da", "rlp = a"]
    if wr.disturbance == "input":
        body += ["v = a + dk", "wind = 0.0"]
    else:
        body += ["v = a", "wind = dk"]
    body.append(f"y = {_output('plant', b['plant'], ['v', 'wind'])}")
    body.append("e = rk - y")
    body.append("ep = e + n" if wr.remnant_at == "error" else "ep = e")
    body += ["ed = buf[bi]", "buf[bi] = ep"]
    if feedforward and not own_ff:
        body += ["rd = rbuf[bi]", "rbuf[bi] = rk"]
    elif own_ff and wr.ff_delay_steps:
        # Its own index: a human's feedforward is often delayed less than the error path.
        body += ["rd = rbuf[fi]", "rbuf[fi] = rk", "fi += 1", f"if fi == {wr.ff_delay_steps}: fi = 0"]
    elif own_ff:
        body.append("rd = rk")
    body += ["bi += 1", f"if bi == {wr.delay_steps}: bi = 0"]
    if wr.threshold is not None:
        t = _lit(wr.threshold)
        body += [f"if ed > {t}: ed = ed - {t}", f"elif ed < -{t}: ed = ed + {t}", "else: ed = 0.0"]
    if wr.gain_drift:
        body.append("ed = kv[k]*ed")
    updates = _update("rem", b["rem"], ["wk"])
    if hess:
        body.append(f"ue = {_lit(wr.Ke)}*ed")
        body.append(f"up = {_output('pf', b['pf'], ['delta'])}")
        if motion:
            body.append(f"om = {_output('motion', b['motion'], ['y'])}")
            body.append(f"uv = {_lit(wr.Km)}*({_output('scc', b['scc'], ['om'])})")
            if wr.motion_delay_steps:
                body += ["uvd = mbuf[mi]", "mbuf[mi] = uv", "mi += 1",
                         f"if mi == {wr.motion_delay_steps}: mi = 0", "uv = uvd"]
            updates += _update("motion", b["motion"], ["y"]) + _update("scc", b["scc"], ["om"])
        else:
            body.append("uv = 0.0")
        body.append("nmin = ue - up - uv")
        updates += _update("nm", b["nm"], ["nmin"]) + _update("pf", b["pf"], ["delta"])
    else:
        updates += _update("eqnm", b["eqnm"], ["ed"])
        if feedforward:
            updates += _update("ffnm", b["ffnm"], ["rd"])
        if vestibular:
            if wr.motion_delay_steps:
                body += ["yv = mbuf[mi]", "mbuf[mi] = y", "mi += 1",
                         f"if mi == {wr.motion_delay_steps}: mi = 0"]
            else:
                body.append("yv = y")
            updates += _update("vnm", b["vnm"], ["yv"])
    if b.get("act") is not None:
        updates += _update("act", b["act"], ["u"])
    updates += _update("plant", b["plant"], ["v", "wind"])
    body += ["ys[k] = y", "us[k] = u", "acts[k] = a"] + updates
    lines = ["def run(r, d, w, g, N, kv=None):"]
    lines += ["    " + s for s in init]
    lines += ["    rlp = 0.0", f"    buf = [0.0]*{wr.delay_steps}", "    bi = 0"]
    if feedforward:
        lines.append(f"    rbuf = [0.0]*{wr.delay_steps if not own_ff else max(wr.ff_delay_steps, 1)}")
    if own_ff:
        lines.append("    fi = 0")
    lines += [
              f"    mbuf = [0.0]*{max(wr.motion_delay_steps, 1)}", "    mi = 0",
              "    ys = [0.0]*N", "    us = [0.0]*N", "    acts = [0.0]*N", "    for k in range(N):"]
    lines += ["        " + s for s in body]
    lines.append("    return ys, us, acts")
    return "\n".join(lines) + "\n"


def compile_loop(wr: Wiring):
    """Return ``run(r, d, w, g, N, kv=None) -> (y, u, a)`` for this wiring.

    ``r``, ``d`` are target and disturbance at every fine step, ``w`` the unit
    remnant noise at every fine step, ``g`` the remnant gain, ``kv`` the visual
    gain's factor at every fine step (read only with ``gain_drift``); ``y`` is the
    output, ``u`` the pilot's control (stick, remnant included when injected
    at the control), ``a`` the actuator output after the rate limit, at every
    fine step.

    Parameters
    ----------
    wr : Wiring
    """
    if wr.delay_steps < 1:
        raise ValueError("the visual delay must be at least one fine step")
    namespace: dict = {}
    exec(compile(_source(wr), "<humanlike-loop>", "exec"), namespace)
    return namespace["run"]
