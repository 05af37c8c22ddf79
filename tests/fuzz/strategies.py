"""Shared hypothesis settings and value strategies for the fuzz tests: any float (NaN, ±inf, huge, subnormal),
derandomized so that CI runs the same examples every time."""

from __future__ import annotations

import math

from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

FUZZ = settings(
    max_examples=50,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
"""Every fuzz property: a fixed, modest number of examples, the same on every run."""

any_float = st.floats(allow_nan=True, allow_infinity=True)
"""Any float: NaN, ±inf, ±1e308, subnormals, ±0."""
nasty_float = st.one_of(
    st.sampled_from([math.nan, math.inf, -math.inf, 1e308, -1e308, 1e9, -1e9, 0.0, -0.0, 5e-324]),
    any_float,
)
"""Any float, with the troublesome ones drawn often."""
vec3 = st.tuples(nasty_float, nasty_float, nasty_float)
quat = st.tuples(nasty_float, nasty_float, nasty_float, nasty_float)
any_int = st.one_of(st.sampled_from([0, -1, 1, 2**31, -(2**31), 2**63]), st.integers(-(2**64), 2**64))


def finite_or_nan(value: float) -> bool:
    return math.isfinite(value) or math.isnan(value)


def all_finite(values) -> bool:
    return all(math.isfinite(v) for v in values)
