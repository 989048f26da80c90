# SPDX-License-Identifier: Apache-2.0
"""Observation and action spaces: gymnasium's Box when gymnasium is importable, else a Box of the
same shape and behaviour (shape, dtype, low, high, sample, contains, seed), so code written for
gymnasium runs unchanged on Debian, which has no gymnasium package."""
import numpy as np

try:  # pragma: no cover - gymnasium is not in Debian; the tests run the fallback
    from gymnasium.spaces import Box  # type: ignore
    HAVE_GYMNASIUM = True
except ImportError:
    HAVE_GYMNASIUM = False

    class Box:
        """A box in R^n: every element between low and high (either may be infinite)."""

        def __init__(self, low, high, shape=None, dtype=np.float32, seed=None):
            self.dtype = np.dtype(dtype)
            if shape is None:
                shape = np.shape(low) if np.ndim(low) else np.shape(high)
            self.shape = tuple(int(n) for n in shape)
            self.low = np.broadcast_to(np.asarray(low, dtype=self.dtype), self.shape).copy()
            self.high = np.broadcast_to(np.asarray(high, dtype=self.dtype), self.shape).copy()
            if np.any(self.low > self.high):
                raise ValueError("a Box's low must not exceed its high")
            self._np_random = None
            if seed is not None:
                self.seed(seed)

        @property
        def np_random(self):
            """The space's random generator (seeded by seed())."""
            if self._np_random is None:
                self.seed()
            return self._np_random

        def seed(self, seed=None):
            """Seeds sample(); returns the seed used, as gymnasium's spaces do."""
            self._np_random = np.random.default_rng(seed)
            return [seed]

        def sample(self):
            """A random element: uniform where both bounds are finite, else normal or exponential."""
            low, high = self.low.astype(np.float64), self.high.astype(np.float64)
            bounded_low, bounded_high = np.isfinite(low), np.isfinite(high)
            out = self.np_random.normal(size=self.shape)
            both = bounded_low & bounded_high
            out[both] = self.np_random.uniform(low[both], high[both])
            only_low = bounded_low & ~bounded_high
            out[only_low] = low[only_low] + self.np_random.exponential(size=int(only_low.sum()))
            only_high = ~bounded_low & bounded_high
            out[only_high] = high[only_high] - self.np_random.exponential(size=int(only_high.sum()))
            return out.astype(self.dtype)

        def contains(self, x):
            """True when x has the shape, a castable dtype and every element within the bounds."""
            x = np.asarray(x)
            if x.shape != self.shape or not np.can_cast(x.dtype, self.dtype, casting="same_kind"):
                return False
            return bool(np.all(x >= self.low) and np.all(x <= self.high))

        def __contains__(self, x):
            return self.contains(x)

        def is_bounded(self, manner="both"):
            """Whether the box is bounded below, above or both."""
            below, above = bool(np.all(np.isfinite(self.low))), bool(np.all(np.isfinite(self.high)))
            return {"both": below and above, "below": below, "above": above}[manner]

        def __eq__(self, other):
            return (isinstance(other, Box) and self.shape == other.shape and self.dtype == other.dtype
                    and np.array_equal(self.low, other.low) and np.array_equal(self.high, other.high))

        def __repr__(self):
            return f"Box({self.low.min()}, {self.high.max()}, {self.shape}, {self.dtype})"

try:  # pragma: no cover
    import gymnasium as _gymnasium  # type: ignore
    EnvBase = _gymnasium.Env
    VectorEnvBase = _gymnasium.vector.VectorEnv
except ImportError:
    EnvBase = object
    VectorEnvBase = object
