"""Deterministic seeds derived from a base seed and names.

Batches must not depend on the order or the number of workers that run
them, so each item's random stream is derived from the base seed and the
item's name (a pilot id, a configuration), never from a shared generator.

One rule for every seed that enters hesspipe (commands, configuration,
library calls): an integer ``0 <= seed < 2**63`` (:func:`check_seed`), so no
two seeds a user can give ever select the same random streams.
"""

from __future__ import annotations

import hashlib
import numbers

from .errors import HesspipeError

#: Largest seed accepted (seeds are non-negative 63-bit integers).
MAX_SEED = 2 ** 63 - 1


def check_seed(seed, what: str = "seed") -> int:
    """Return `seed` as an int if it is an integer ``0 <= seed <= MAX_SEED``.

    Parameters
    ----------
    seed : int
        The seed to check.
    what : str
        How the caller names it (for the message).

    Raises
    ------
    HesspipeError
        Naming `what` (the parameter or field) and the rule; a negative or too
        large seed is refused, never wrapped onto another seed.
    """
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or not 0 <= seed <= MAX_SEED:
        raise HesspipeError(f"{what}: expected an integer 0 <= seed < 2**63, got {seed!r}")
    return int(seed)


def derive_seed(base: int, *keys: str) -> int:
    """Return a 63-bit seed determined by `base` and the strings `keys`.

    The keys are hashed with SHA-256 (Python's ``hash`` is salted per
    process) and mixed with `base` by :class:`numpy.random.SeedSequence`.
    `base` must satisfy :func:`check_seed`.

    Parameters
    ----------
    base : int
        The user's seed.
    *keys : str
        What the seed is for (stage, pilot id, run ...); order matters.
    """
    import numpy as np  # here, not at import: the command line checks seeds at start-up

    base = check_seed(base)
    words = [base & 0xFFFFFFFF, base >> 32]
    for key in keys:
        digest = hashlib.sha256(str(key).encode("utf-8")).digest()
        words.extend(int.from_bytes(digest[i:i + 4], "little") for i in range(0, 16, 4))
    return int(np.random.SeedSequence(words).generate_state(1, dtype=np.uint64)[0] >> 1)
