"""Flash temperature of a uniform circular heat source (pipeline.physics.flash_temperature): the exact
moving-source solution against its published limits (the stationary source of Carslaw & Jaeger, the 1-D
high-speed limit of Jaeger), Tian & Kennedy's closed forms against both limits and against the exact
solution between them, and the heat partition of Blok's postulate."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.physics import flash_temperature as ft


def _disk_mean(pe: float, n_r: int = 16, n_phi: int = 32, nodes: int = 800) -> float:
    """The exact solution's mean over the source: Gauss-Legendre in r^2 (uniform in area), midpoint in phi."""
    x, w = np.polynomial.legendre.leggauss(n_r)
    r = np.sqrt(0.5 * (x + 1.0))  # r^2 uniform on [0, 1]: the area weight
    phis = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    total = 0.0
    for ri, wi in zip(r, w):
        total += wi * np.mean([ft.moving_source_temperature(ri * np.cos(p), ri * np.sin(p), pe, nodes) for p in phis])
    return 0.5 * total


def test_stationary_source_has_carslaw_jaegers_centre_and_mean():
    # [CJ59] 10.5: centre q a / k, mean 8 q a / (3 pi k)
    # tol: the midpoint rule on R = 1 at every node: exact up to the rounding of the mean
    assert ft.moving_source_temperature(0.0, 0.0, 0.0) == pytest.approx(1.0, rel=1e-12)
    # tol: the edge's sqrt singularity in theta at the midpoint rule's 2000 points
    assert ft.moving_source_temperature(1.0, 0.0, 0.0) == pytest.approx(2 / np.pi, rel=1e-3)  # edge: 2/pi [CJ59]
    # tol: the 16 x 32 area quadrature of a function with a sqrt edge
    assert _disk_mean(0.0) == pytest.approx(8 / (3 * np.pi), rel=2e-3)
    # tol: a closed form evaluated at Pe = 0: one or two roundings
    assert ft.flash_factor(0.0, "max") == pytest.approx(1.0, rel=1e-15)
    # tol: a closed form evaluated at Pe = 0: one or two roundings
    assert ft.flash_factor(0.0, "mean") == pytest.approx(8 / (3 * np.pi), rel=1e-15)


def test_high_peclet_mean_is_the_beta_function_closed_form_to_the_last_bit():
    from scipy.special import beta
    assert ft.MEAN_HIGH_PE == float(8.0 * beta(0.5, 1.75) / (3.0 * np.pi ** 1.5))


def test_high_peclet_limit_is_the_one_dimensional_half_space():
    # [Jaeger42]: T = (2 q / k) sqrt(kappa x / (pi V)): at the trailing end of the central chord (x = 2a)
    # 2 / sqrt(pi Pe); the exact solution approaches it as Pe grows, the closed form has it as its limit
    for pe in (100.0, 1000.0):
        exact = max(ft.moving_source_temperature(x, 0.0, pe, 20000) for x in np.linspace(-1.0, -0.98, 41))
        # tol: the exact solution's 1/sqrt(Pe) correction (lateral conduction) at Pe >= 100
        assert exact * np.sqrt(np.pi * pe) / 2 == pytest.approx(1.0, rel=0.02)
    for pe in (1e6, 1e8):
        # tol: the offset 4/pi against Pe: relative 2/pi / Pe
        assert ft.flash_factor(pe, "max") * np.sqrt(np.pi * pe) / 2 == pytest.approx(1.0, rel=1e-6)
        assert ft.flash_factor(pe, "mean") * np.sqrt(pe) == pytest.approx(ft.MEAN_HIGH_PE, rel=1e-6)
    # the 1-D solution averaged over the disk: int_disk (2/sqrt(pi)) sqrt(x / Pe') dA / pi, by direct quadrature
    y, wy = np.polynomial.legendre.leggauss(200)
    chord = 2 * np.sqrt(1 - y**2)
    mean = float(np.sum(wy * (2 / np.sqrt(np.pi)) * (2 / 3) * chord**1.5 / np.sqrt(2))) / np.pi  # Pe = V a/(2 kappa)
    # tol: Gauss-Legendre on the (1 - y^2)^(3/4) end singularity at 200 points
    assert mean == pytest.approx(ft.MEAN_HIGH_PE, rel=1e-4)
    assert ft.MEAN_HIGH_PE == pytest.approx(0.6885, abs=1e-4)


@pytest.mark.parametrize("pe", [0.01, 0.1, 1.0, 5.0, 20.0])
def test_closed_forms_follow_the_exact_solution_between_the_limits(pe):
    xs = np.linspace(-1.0, 0.0, 201)
    exact_max = max(ft.moving_source_temperature(x, 0.0, pe, 4000) for x in xs)
    # tol: [TK94]'s maximum is within 2.5 % of the exact one over all Pe (measured: at most 2.2 % at Pe ~ 1)
    assert ft.flash_factor(pe, "max") == pytest.approx(exact_max, rel=0.025)
    # tol: the mean's interpolation is within 5 % (measured: at most 4.0 % at Pe ~ 1)
    assert ft.flash_factor(pe, "mean") == pytest.approx(_disk_mean(pe), rel=0.05)


def test_factors_fall_with_peclet_and_refuse_bad_input():
    pes = np.logspace(-3, 4, 50)
    for kind in ("max", "mean"):
        f = ft.flash_factor(pes, kind)
        assert np.all(np.diff(f) < 0)
    assert np.all(ft.flash_factor(pes, "mean") < ft.flash_factor(pes, "max"))
    with pytest.raises(ValueError, match="Peclet number must be >= 0"):
        ft.flash_factor(-1.0)
    with pytest.raises(ValueError, match="kind must be"):
        ft.flash_factor(1.0, "median")
    with pytest.raises(ValueError, match="inside the source"):
        ft.moving_source_temperature(1.0, 1.0, 1.0)


def test_heat_partition_equalises_the_mean_temperatures():
    # two equal bodies both stationary: half each; a moving disk cools faster, so takes more
    # tol: 1/2 of two equal terms: exact up to one rounding
    assert ft.heat_partition(10.0, 10.0, 0.0) == pytest.approx(0.5, rel=1e-15)
    assert ft.heat_partition(10.0, 10.0, 10.0) < 0.5
    for ks, kd, pe in ((20.0, 1.1, 80.0), (20.0, 150.0, 0.7)):
        b = ft.heat_partition(ks, kd, pe)
        slider = b / ks * ft.flash_factor(0.0, "mean")
        disk = (1 - b) / kd * ft.flash_factor(pe, "mean")
        # tol: the partition's own definition recomputed: a few roundings
        assert slider == pytest.approx(disk, rel=1e-12)
    # a perfect conductor under the slider takes all of it
    assert ft.heat_partition(20.0, 1e12, 1.0) == pytest.approx(0.0, abs=1e-9)


def test_contact_temperature_scales_and_limits():
    base = dict(power=17e-3, area=2.4e-12, count=440.0, speed=19.5, k_slider=20.0, k_disk=1.1,
                diffusivity_disk=5.4e-7)
    t = ft.contact_temperature(**base)
    a = np.sqrt(2.4e-12 / (np.pi * 440))
    # tol: the same products recomputed: a few roundings
    assert t["radius"] == pytest.approx(a, rel=1e-12)
    # tol: the same products recomputed: a few roundings
    assert t["peclet"] == pytest.approx(19.5 * a / (2 * 5.4e-7), rel=1e-12)
    q = 17e-3 / 2.4e-12
    # tol: the same products recomputed: a few roundings
    assert t["temperature"] == pytest.approx(t["partition"] * q * a / 20.0, rel=1e-12)
    # tol: a ratio of two closed-form constants: a few roundings
    assert t["mean_temperature"] / t["temperature"] == pytest.approx(8 / (3 * np.pi), rel=1e-12)
    # linear in the power; fewer, larger spots of the same area run hotter (a ~ count^-1/2)
    assert ft.contact_temperature(**{**base, "power": 34e-3})["temperature"] == pytest.approx(2 * t["temperature"])
    assert ft.contact_temperature(**{**base, "count": 110.0})["temperature"] > t["temperature"]
    assert np.isnan(ft.contact_temperature(**{**base, "power": 0.0})["temperature"])
    assert np.isnan(ft.contact_temperature(**{**base, "count": 0.0})["partition"])
