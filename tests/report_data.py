"""Hand-made datasets of a results folder for the report (sweep, histories, calibration, DMW, roughness),
written into ``out`` as the stages would, and the checks of a drawn PNG and a summary CSV; shared by the
report tests and the tests that run ``hdi report`` on such a folder."""

from __future__ import annotations

import csv
import matplotlib.image as mpimg
import numpy as np
import xarray as xr
from pipeline.io import write_dataset
from pipeline.variables import HISTORIES, SCALARS


PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
PROT = np.round(np.arange(0.0, 6.01, 0.5), 9)          # 13 protrusions [nm]
FIRST_CONTACT = 3.0
K = 0.4454


def _scalar_var(name, values, dims):
    return SCALARS[name].data(values, dims)


def slice_values(scale: float = 1.0) -> dict[str, np.ndarray]:
    """One roughness/damping slice: flying below 3 nm, bouncing at 3-3.5 nm, surfing from 4 nm."""
    n = PROT.size
    regime = np.where(PROT < FIRST_CONTACT, 0, np.where(PROT < 4.0, 1, 2))
    contact = regime > 0
    clearance = np.where(contact, -0.1 * (PROT - 2.5), 3.0 - PROT + 0.2)
    fhm = np.where(regime == 0, 9.0 + 0.5 * PROT, np.where(regime == 1, 20.0, 1.0 + 0.1 * (PROT - 4)))
    fhm = fhm * scale
    interference = np.where(contact, -clearance, np.nan)
    pressure = np.where(contact, 400.0 + 10 * PROT, np.nan)
    shear = np.where(contact, 300.0 + 2 * PROT, np.nan)
    return {
        "fhm_bv": fhm, "clearance": clearance, "min_clearance": clearance - 0.5,
        "interference": interference,
        "contact_force": np.where(contact, 1.0 + 0.1 * PROT, 0.0),
        "friction_force": np.where(contact, 0.7 + 0.05 * PROT, 0.0),
        "adhesion_force": 0.01 + 0.2 * PROT,
        "net_force": np.where(contact, 1.0, 0.0) - (0.01 + 0.2 * PROT),
        "friction_coefficient": shear / pressure,
        "mean_pressure": pressure, "shear_stress": shear,
        "real_area": np.where(contact, 4.0, np.nan),
        "nominal_area": np.linspace(120.0, 60.0, n),
        "protrusion_radius": np.linspace(2000.0, 700.0, n),
        "contact_fraction": np.where(regime == 2, 1.0, np.where(regime == 1, 0.5, 0.0)),
        "regime": regime,
    }


def write_sweep(out, dampings=(0.05,), scales=None):
    scales = scales or {d: 1.0 for d in dampings}
    dims = ("protrusion", "roughness", "damping")
    per = [slice_values(scales[d]) for d in dampings]
    data = {name: _scalar_var(name, np.stack([p[name] for p in per], axis=-1)[:, None, :], dims)
            for name in per[0]}
    coords = {"protrusion": ("protrusion", PROT, {"units": "nm", "long_name": "TFC protrusion"}),
              "roughness": ("roughness", np.array(["scene"], dtype=object), {"units": "1", "long_name": "set"}),
              "damping": ("damping", np.array(dampings, float), {"units": "1", "long_name": "damping ratio"})}
    write_dataset(xr.Dataset(data, coords=coords), out / "sweep.nc", stage="sweep",
                  extra_attrs={"k": K, "k_source": "scene (contact.k)", "steady_window": "0.5 ms to 2 ms",
                               "fhm_measure": "peak-to-peak"})


def write_histories(out):
    t = np.arange(400) * 2.5e-6                      # 1 ms
    prot = np.array([1.0, 5.0])
    rng = np.random.default_rng(1)
    shape = (2, 1, 1, t.size)
    wave = np.sin(2 * np.pi * 20e3 * t) + 0.3 * rng.standard_normal(t.size)
    contact = np.stack([np.zeros_like(t), (t > 1e-4).astype(float)])
    sep = np.stack([4.0 + 0.6 * wave, -0.2 + 0.05 * wave])
    values = {
        "separation": sep, "clearance": sep - 0.23, "in_contact": contact,
        "contact_force": contact * (1.5 + 0.1 * wave), "friction_force": contact * (1.0 + 0.07 * wave),
        "adhesion_force": np.stack([0.02 + 0 * t, 2.0 + 0.01 * wave]),
        "net_force": contact * (1.5 + 0.1 * wave) - 2.0,
        "friction_coefficient": np.where(contact > 0, 0.7 + 0.01 * wave, np.nan),
        "mean_pressure": np.where(contact > 0, 440 + 5 * wave, np.nan),
        "shear_stress": np.where(contact > 0, 312 + 1 * wave, np.nan),
    }
    dims = ("protrusion", "roughness", "damping", "elapsed_time")
    data = {n: xr.Variable(dims, v.reshape(shape), attrs=HISTORIES[n].attrs())
            for n, v in values.items()}
    coords = {"protrusion": ("protrusion", prot, {"units": "nm", "long_name": "TFC protrusion"}),
              "roughness": ("roughness", np.array(["scene"], dtype=object), {"units": "1", "long_name": "set"}),
              "damping": ("damping", [0.05], {"units": "1", "long_name": "damping ratio"}),
              "elapsed_time": ("elapsed_time", t, {"units": "s", "long_name": "elapsed time"})}
    write_dataset(xr.Dataset(data, coords=coords), out / "sweep_histories.nc", stage="sweep")


def write_calibration(out):
    ks = np.linspace(-1.0, 1.0, 5)
    data = {"touchdown": ("k", [3.5, 3.0, 3.0, 2.5, np.nan], {"units": "nm", "long_name": "first contact"})}
    for name, v in (("k_calibrated", 0.25), ("k_low", 0.0), ("k_high", 0.5), ("k_onset", 0.0), ("k_previous", 0.5),
                    ("contact_probability_one_sided", 0.4), ("contact_probability_two_sided", 0.8)):
        data[name] = ((), v, {"units": "1", "long_name": name})
    ds = xr.Dataset(data, coords={"k": ("k", ks, {"units": "1", "long_name": "k"})})
    write_dataset(ds, out / "calibration.nc", stage="calibrate",
                  extra_attrs={"outcome": "admissible k in (0, 0.5]", "touchdown_onset_nm": 3.0,
                               "touchdown_previous_nm": 2.5})


def write_dmw(out):
    fs, n = 4e6, 4000
    rng = np.random.default_rng(2)
    w = np.convolve(rng.standard_normal(n), np.ones(20) / 20, mode="same")
    f = np.fft.rfftfreq(n, 1 / fs)
    psd = np.abs(np.fft.rfft(w)) ** 2 / (fs * n)
    ds = xr.Dataset({
        "displacement": ("elapsed_time", w, {"units": "nm", "long_name": "DMW"}),
        "psd": ("frequency", psd, {"units": "nm2 Hz-1", "long_name": "PSD"}),
        "rms": ((), float(np.std(w)), {"units": "nm", "long_name": "rms"}),
        "band_low": ((), 10e3, {"units": "Hz", "long_name": "band low"}),
        "band_high": ((), 500e3, {"units": "Hz", "long_name": "band high"}),
    }, coords={"elapsed_time": ("elapsed_time", np.arange(n) / fs, {"units": "s", "long_name": "elapsed time"}),
               "frequency": ("frequency", f, {"units": "Hz", "long_name": "frequency"})})
    write_dataset(ds, out / "dmw.nc", stage="dmw", extra_attrs={"dmw_source": "synthetic", "seed": 2})


def write_roughness(out):
    surfaces = np.array(["disk", "tfc", "combined"], dtype=object)
    sm = ("surface", "route")
    vals = {"sigma": [[0.4, 0.41], [0.3, 0.31], [0.5, np.nan]], "sigma_s": [[0.3, 0.3], [0.2, 0.2], [0.35, np.nan]],
            "summit_radius": [[4.0, 3.0], [6.0, 5.0], [5.0, np.nan]],
            "summit_density": [[12.0, 9.0], [8.0, 7.0], [10.0, np.nan]]}
    units = {"sigma": "nm", "sigma_s": "nm", "summit_radius": "um", "summit_density": "um-2"}
    data = {k: (sm, np.array(v), {"units": units[k], "long_name": k}) for k, v in vals.items()}
    data["pixel_size"] = ("surface", [5.0, 5.0, np.nan], {"units": "nm", "long_name": "pixel size"})
    ds = xr.Dataset(data, coords={"surface": ("surface", surfaces, {"units": "1", "long_name": "surface"}),
                                  "route": ("route", np.array(["spectral", "summits"], dtype=object),
                                             {"units": "1", "long_name": "route"})})
    write_dataset(ds, out / "roughness.nc", stage="roughness")


def check_png(path):
    assert path.is_file(), path
    raw = path.read_bytes()
    assert raw[:8] == PNG_SIGNATURE, f"{path.name} is not a PNG"
    assert len(raw) > 5_000, f"{path.name} is only {len(raw)} bytes"
    img = mpimg.imread(path)
    assert img.ndim == 3 and img.shape[0] > 300 and img.shape[1] > 500
    rgb = img[..., :3].reshape(-1, 3)
    assert rgb.var(axis=0).sum() > 1e-3, f"{path.name} is (nearly) a single colour"
    q = (rgb * 255).astype(np.int64)
    colours = np.unique(q[:, 0] * 65536 + q[:, 1] * 256 + q[:, 2])
    assert colours.size > 20, f"{path.name} has too few colours"


def read_csv(path):
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], rows[1:]
