"""Wind: mean, gust statistics (Gauss–Markov), on/off, seeding."""

from __future__ import annotations

import math
import random
import statistics

import pytest

from stack.sim.wind import WindModel, WindParams


def series(model: WindModel, dt: float, n: int) -> list[tuple[float, float, float]]:
    return [model.update(dt) for _ in range(n)]


def test_calm_and_disabled_wind_is_exactly_zero() -> None:
    calm = WindModel(WindParams(), random.Random(1))
    assert series(calm, 0.004, 10) == [(0.0, 0.0, 0.0)] * 10
    gusty = WindModel(WindParams(mean_ned=(3.0, 0.0, 0.0), gust_std_horizontal=2.0), random.Random(1))
    gusty.set_enabled(False)
    assert series(gusty, 0.004, 10) == [(0.0, 0.0, 0.0)] * 10
    gusty.set_enabled(True)
    assert gusty.update(0.004) != (0.0, 0.0, 0.0)


def test_steady_wind_without_gusts() -> None:
    model = WindModel(WindParams.from_speed_direction(5.0, 90.0), random.Random(3))
    # Wind from the east blows towards the west.
    assert model.update(0.004) == pytest.approx((0.0, -5.0, 0.0), abs=1e-12)


def test_gust_statistics_match_the_configured_figures() -> None:
    tau, dt = 2.0, 0.004
    params = WindParams(mean_ned=(4.0, -1.0, 0.0), gust_std_horizontal=2.0, gust_std_vertical=0.5,
                        gust_time_constant=tau)
    samples = series(WindModel(params, random.Random(7)), dt, 300_000)  # 1200 s = 600 τ
    for axis, (mean, sigma) in enumerate(((4.0, 2.0), (-1.0, 2.0), (0.0, 0.5))):
        x = [s[axis] for s in samples]
        assert statistics.fmean(x) == pytest.approx(mean, abs=0.25 * sigma)
        assert statistics.pstdev(x) == pytest.approx(sigma, rel=0.1)
        # Autocorrelation at lag τ is e^-1 for a first-order Gauss–Markov process.
        lag = round(tau / dt)
        m = statistics.fmean(x)
        d = [v - m for v in x]
        rho = sum(a * b for a, b in zip(d[:-lag], d[lag:], strict=True)) / sum(v * v for v in d)
        assert rho == pytest.approx(math.exp(-1.0), abs=0.08)


def test_gusts_are_seeded() -> None:
    params = WindParams(gust_std_horizontal=1.0, gust_std_vertical=1.0)
    a = series(WindModel(params, random.Random("1/wind")), 0.004, 100)
    b = series(WindModel(params, random.Random("1/wind")), 0.004, 100)
    c = series(WindModel(params, random.Random("2/wind")), 0.004, 100)
    assert a == b
    assert a != c


def test_invalid_parameters_are_rejected() -> None:
    with pytest.raises(ValueError):
        WindParams(gust_std_horizontal=-1.0)
    with pytest.raises(ValueError):
        WindParams(gust_time_constant=0.0)
    with pytest.raises(ValueError):
        WindParams(mean_ned=(math.nan, 0.0, 0.0))


def test_the_surface_layer_slows_the_wind_logarithmically_toward_the_ground():
    from stack.sim.wind import ROUGHNESS_LENGTH, surface_layer_factor

    assert surface_layer_factor(5.0, 0.0) == 1.0  # no profile: the same wind at every height
    assert surface_layer_factor(12.0, 10.0) == 1.0 and surface_layer_factor(0.0, 10.0) == 0.0
    assert surface_layer_factor(1.0, 10.0) == pytest.approx(math.log(1.0 / 0.03) / math.log(10.0 / 0.03))
    assert surface_layer_factor(ROUGHNESS_LENGTH, 10.0) == 0.0
    model = WindModel(WindParams(mean_ned=(0.0, 8.0, 0.0), reference_height=10.0), random.Random(1))
    model.update(0.004)
    assert model.at_height(1.0)[1] == pytest.approx(8.0 * math.log(1.0 / 0.03) / math.log(10.0 / 0.03))
    assert model.at_height(40.0) == model.wind
