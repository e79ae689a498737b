"""Deterministic seeds derived from a base seed and names.

Batches must not depend on the order or the number of workers that run
them, so each item's random stream is derived from the base seed and the
item's name (a pilot id, a configuration), never from a shared generator.
"""

from __future__ import annotations

import hashlib

import numpy as np


def derive_seed(base: int, *keys: str) -> int:
    """Return a 63-bit seed determined by `base` and the strings `keys`.

    The keys are hashed with SHA-256 (Python's ``hash`` is salted per
    process) and mixed with `base` by :class:`numpy.random.SeedSequence`.
    """
    words = [int(base) & 0xFFFFFFFF, (int(base) >> 32) & 0xFFFFFFFF]
    for key in keys:
        digest = hashlib.sha256(str(key).encode("utf-8")).digest()
        words.extend(int.from_bytes(digest[i:i + 4], "little") for i in range(0, 16, 4))
    return int(np.random.SeedSequence(words).generate_state(1, dtype=np.uint64)[0] >> 1)
