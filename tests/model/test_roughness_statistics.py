"""The roughness statistics of a scene's surfaces and their combination (pipeline.model.roughness_statistics;
docs/model.md, sections "Combined surface" and "Asperity statistics").

Known answers for explicit surfaces (McCool's relations: eta = m4 / (6 pi sqrt 3 m2), R = 0.375 sqrt(pi / m4)):
the spectral moments of independent surfaces add, so two surfaces of rms 0.4 and 0.3 nm combine to 0.5 nm,
two of one summit radius R to R / sqrt 2 (m4 doubles) and of one summit density to the same density (m2 and
m4 double); the plasticity index is Greenwood and Williamson's (E'/H) sqrt(sigma_s / R).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pipeline.config.scene import scene_from_dict
from pipeline.io import DatasetError
from pipeline.model import roughness_statistics as rs
from pipeline.physics import surface as sf

ETA = 13.3e-6   # [nm^-2] 13.3 um^-2, the paper scene's summit density
R_NM = 5000.0   # [nm] 5 um, the paper scene's summit radius


@pytest.fixture(scope="module")
def two():
    """Two explicit surfaces (rms 0.4 and 0.3 nm, the paper's eta and R) and a scene with a hardness."""
    surfaces = [sf.from_statistics(0.4, ETA, R_NM, label="a"), sf.from_statistics(0.3, ETA, R_NM, label="b")]
    return rs.build_dataset(surfaces, scene_from_dict({"materials": {"hardness_gpa": 5.0}}))


def test_combined_surface_adds_the_moments(two):
    spectral = two.sel(route="spectral")
    assert list(two["surface"].values) == ["a", "b", rs.COMBINED]
    # tol: moments and McCool's relations of exact decimals, a few roundings
    np.testing.assert_allclose(spectral["sigma"].values, [0.4, 0.3, 0.5], rtol=1e-12)
    # tol: moments and McCool's relations of exact decimals, a few roundings
    np.testing.assert_allclose(spectral["summit_radius"].values, [5.0, 5.0, 5.0 / math.sqrt(2)], rtol=1e-12)  # [um]
    # tol: moments and McCool's relations of exact decimals, a few roundings
    np.testing.assert_allclose(spectral["summit_density"].values, [13.3, 13.3, 13.3], rtol=1e-12)  # [um^-2]
    # tol: moments and McCool's relations of exact decimals, a few roundings
    np.testing.assert_allclose(two["m0"].values, [0.16, 0.09, 0.25], rtol=1e-12)  # [nm^2]
    assert two["sigma"].attrs["units"] == "nm" and two["summit_radius"].attrs["units"] == "um"
    # explicit statistics have no height map: the summit route is empty
    assert np.all(np.isnan(two.sel(route="summits")["sigma"].values))


def test_plasticity_index_is_greenwood_williamson(two):
    spectral = two.sel(route="spectral")
    E, H = two.attrs["composite_modulus_gpa"], two.attrs["hardness_gpa"]
    assert H == 5.0 and E == pytest.approx(94.19, rel=1e-3)  # E' of the paper's materials
    expected = E / H * np.sqrt(spectral["sigma_s"].values / (spectral["summit_radius"].values * 1e3))
    # tol: the same formula on the same numbers, a few roundings
    np.testing.assert_allclose(spectral["plasticity_index"].values, expected, rtol=1e-12)
    # without a scene (no hardness) the indices are NaN
    alone = rs.build_dataset([sf.from_statistics(0.4, ETA, R_NM)])
    assert np.all(np.isnan(alone["plasticity_index"].values))


def test_combined_statistics_reads_the_combined_row(two, tmp_path):
    s = rs.combined_statistics(two)
    # tol: moments and McCool's relations of exact decimals, a few roundings
    assert s["sigma_nm"] == pytest.approx(0.5, rel=1e-12)
    # tol: moments and McCool's relations of exact decimals, a few roundings
    assert s["summit_radius_um"] == pytest.approx(5.0 / math.sqrt(2), rel=1e-12)
    # tol: moments and McCool's relations of exact decimals, a few roundings
    assert s["summit_density_per_um2"] == pytest.approx(13.3, rel=1e-12)
    # McCool: y_s = 4 sigma / sqrt(pi alpha), sigma_s^2 = sigma^2 - 3.717e-4 / (eta R)^2
    # (alpha here is m0 m4 / m2^2; y_s takes McCool's 2412.74 (sigma eta R)^2, rounded: 7e-7 apart)
    assert s["y_s_nm"] == pytest.approx(4 * 0.5 / math.sqrt(math.pi * s["alpha"]), rel=1e-5)
    eta_r = s["summit_density_per_um2"] * s["summit_radius_um"]
    # tol: McCool's relation rearranged, a few roundings
    assert s["sigma_s_nm"] ** 2 == pytest.approx(0.25 - 3.717e-4 / (eta_r * 1e-3) ** 2, rel=1e-9)


def test_bad_routes_and_missing_rows_are_errors(two):
    with pytest.raises(ValueError, match=r"route 'sideways': expected one of \('spectral', 'summits'\)"):
        rs.combined_statistics(two, "sideways")
    with pytest.raises(DatasetError, match=r"the 'summits' route has no combined statistics .* use route='spectral'"):
        rs.combined_statistics(two, "summits")
    with pytest.raises(DatasetError, match="no 'combined' surface"):
        rs.combined_statistics(two.sel(surface=["a", "b"]))


def test_an_error_on_a_dataset_in_memory_is_one_line(two):
    with pytest.raises(DatasetError) as exc:
        rs.combined_statistics(two, "summits")
    assert "\n" not in str(exc.value) and str(exc.value).startswith("the roughness dataset in memory: ")


def test_files_get_unique_labels(repo_root):
    scan = repo_root / "tests" / "data" / "afm" / "di-3.di"
    labels = [s.label for s in rs.summaries([scan, scan], None, "plane")]
    assert labels == ["di-3", "di-3-2"]
