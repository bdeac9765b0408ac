"""One way to turn the ``rng`` argument of every stochastic entry point into a Generator."""

from __future__ import annotations

import numpy as np

RNGLike = np.random.Generator | int | np.random.SeedSequence | None


def as_generator(rng: RNGLike = None) -> np.random.Generator:
    """Return a ``numpy.random.Generator`` for ``rng``.

    A Generator is passed through unchanged (so callers share one stream); an int or
    SeedSequence seeds a new PCG64 generator; ``None`` draws fresh OS entropy.
    """
    if isinstance(rng, np.random.Generator):
        return rng
    return np.random.default_rng(rng)


def seed_of(rng: RNGLike) -> int | None:
    """The integer seed behind ``rng`` when there is one (for reports), else ``None``."""
    if isinstance(rng, (int, np.integer)):
        return int(rng)
    return None
