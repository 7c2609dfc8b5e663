"""Type aliases shared across camjax (jaxtyping shapes where they add information)."""

from __future__ import annotations

from typing import TypeAlias

import jax
import numpy as np
from jaxtyping import Array, Float

ArrayLike: TypeAlias = jax.Array | np.ndarray | float
LawValues: TypeAlias = tuple[jax.Array, jax.Array, jax.Array, jax.Array]
"""``(s, v, a, j)`` of a motion law, each shaped like the ``tau`` it was evaluated at."""
Breakpoints: TypeAlias = tuple[float, ...] | Float[Array, " b"]
