"""``sweep.nc`` and ``sweep_histories.nc`` assembled from the sweep's parts (:class:`Assembler`).

The parts are the datasets of the sweep's batches (:func:`pipeline.model.simulation.simulate` at a batch's
protrusions, :class:`pipeline.model.sweep_parts.Batch`), added in any order, as they return from the fan-out or
as read back from the files of an earlier run (:func:`pipeline.model.sweep_parts.kept_parts`); the datasets do
not depend on that order. Along ``roughness`` each set carries the statistics its interface model used
(:func:`roughness_coordinates`); with DMW realisations the ensemble statistics of
:func:`pipeline.analyses.ensemble_rules.statistics` are added.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import xarray as xr

from ..config.grid import roughness_sets, same_point, scene_label
from ..config.heater_power import power_coordinates
from ..model.interface_tables import roughness_record
from ..model.simulation import DIRECTIONS
from ..model.sweep_parts import Batch
from ..variables import COORDINATES, ENSEMBLE, HISTORIES, SCALARS, STEPPING, TIME, coordinate
from . import ensemble_rules as ensemble


class Assembler:
    """``sweep.nc`` and ``sweep_histories.nc`` filled part by part: :meth:`add` as each batch's part arrives
    (the sweep calls it from the fan-out's ``on_done``, so the filling overlaps the batches still running),
    :meth:`datasets` once every part is in.

    A part's values go to its batch's slots (disjoint), and the variables are ordered as they first appear
    in batch order (not in the order the parts arrive), so the datasets do not depend on the order of
    :meth:`add` calls: a 2-worker run gives the file of a 1-worker run.
    """

    def __init__(self, scene: Any, prot: np.ndarray, labels: list[str], damp: list[float], n_real: int = 1):
        self.scene, self.prot, self.labels, self.damp, self.n_real = scene, prot, labels, damp, n_real
        self.stepping = scene["sweep"]["protocol"] == "stepping"
        # (stepping: the scalars per pass, before the realisation, whose statistics reduce the last axis)
        self.shape = (len(prot), len(labels), len(damp)) + ((len(DIRECTIONS),) if self.stepping else ()) \
            + ((n_real,) if n_real > 1 else ())
        self.chain_shape = (len(labels), len(damp)) + ((n_real,) if n_real > 1 else ())
        self.arrays: dict[str, np.ndarray] = {}
        self.chains: dict[str, np.ndarray] = {}
        self.hist: dict[str, np.ndarray] = {}
        self.hist_prot: np.ndarray | None = None
        self.time: np.ndarray | None = None
        self._time_from: int | None = None  # (the batch whose time axis the histories use: the first in batch order)
        self._first: dict[str, tuple[int, int]] = {}  # variable -> (batch index, position) of its first appearance
        self.added: set[int] = set()
        self._histories: xr.Dataset | None = None  # (made by :meth:`histories`, until a part with histories comes)

    def _seen(self, name: str, batch: int, position: int) -> None:
        at = (batch, position)
        if name not in self._first or at < self._first[name]:
            self._first[name] = at

    def add(self, b: Batch, ds: xr.Dataset) -> None:
        """Put the part ``ds`` of batch ``b`` into the arrays."""
        r, d = self.labels.index(b.label), self.damp.index(b.damping)
        real = (b.realisation,) if self.n_real > 1 else ()
        values = {name: ds.variables[name].values for name in ds.variables}  # (no DataArray per name: main thread)
        for i, name in enumerate(ds.data_vars):
            self._seen(name, b.index, i)
            if name.startswith("h_"):
                continue
            if name in STEPPING:  # one value per chain
                self.chains.setdefault(name, np.full(self.chain_shape, np.nan))[(r, d) + real] = values[name]
                continue
            if name not in self.arrays:  # NaN: not computed (regime: its declared _FillValue on disk)
                self.arrays[name] = np.full(self.shape, np.nan)
            at = (list(b.indices), r, d) + ((slice(None),) if self.stepping else ()) + real
            self.arrays[name][at] = values[name]
        if "hist_protrusion" in ds.coords:
            self._histories = None
            if self.hist_prot is None:
                sweep, report = self.scene["sweep"], self.scene["report"]
                self.hist_prot = np.array([h for h in sweep["histories_nm"] or report["histories_nm"]
                                           if np.any(same_point(self.prot, h))])
            if self._time_from is None or b.index < self._time_from:
                self.time, self._time_from = values[TIME], b.index
            for name in ds.data_vars:
                if name.startswith("h_"):
                    base = name[2:]
                    if base not in self.hist:
                        self.hist[base] = np.full((len(self.hist_prot), len(self.labels), len(self.damp),
                                                   values[TIME].size), np.nan)
                    for i, hp in enumerate(values["hist_protrusion"]):
                        j = int(np.argmin(np.abs(self.hist_prot - hp)))
                        self.hist[base][j, r, d] = values[name][i]
        self.added.add(b.index)

    def _ordered(self, values: dict[str, np.ndarray], prefix: str = "") -> dict[str, np.ndarray]:
        """``values`` in the order their variables (``prefix + name``) first appear in batch order."""
        return {name: values[name] for name in sorted(values, key=lambda n: self._first[prefix + n])}

    def datasets(self, key: str, k_source: str, attrs: dict, seeds: list[int] | None = None,
                 run: dict[str, xr.Variable] | None = None, *,
                 statistics: dict[str, dict[str, Any]]) -> dict[str, xr.Dataset | None]:
        """``sweep.nc`` and ``sweep_histories.nc`` from the parts added.

        ``run``: the run's values (:func:`pipeline.model.simulation.grid_run_values`: 0-d, or along
        ``roughness`` or ``damping``), written into both datasets. ``statistics``: each roughness set's
        statistics as its interface model used them (label ->
        :func:`pipeline.model.interface_tables.used_statistics`), which become coordinates along ``roughness``
        (:func:`roughness_coordinates`) and, with the scans' hashes, the JSON attribute ``roughness_sets``
        (:func:`roughness_record`). With more than one realisation the scalars gain a last dimension
        ``realisation`` and the ensemble statistics of :func:`pipeline.analyses.ensemble_rules.statistics`
        are added.
        """
        n_real, stepping = self.n_real, self.stepping
        coords = self._coords(statistics)
        real = ("realisation",) if n_real > 1 else ()
        dims = ("protrusion", "roughness", "damping") + (("direction",) if stepping else ()) + real
        data = {name: SCALARS[name].data(a, dims) for name, a in self._ordered(self.arrays).items()}
        data.update({name: STEPPING[name].data(a, ("roughness", "damping") + real)
                     for name, a in self._ordered(self.chains).items()})
        if n_real > 1:
            data["dmw_seed"] = ENSEMBLE["dmw_seed"].data(np.array(seeds), ("realisation",))
            data.update(ensemble.statistics(data))
        ds = xr.Dataset(data, coords=coords).assign(run or {})
        ds.attrs.update(self._attrs(k_source, attrs, statistics))
        return {"sweep.nc": ds, "sweep_histories.nc": self.histories(k_source, attrs, run, statistics=statistics)}

    def _coords(self, statistics: dict[str, dict[str, Any]]) -> dict[str, xr.Variable]:
        """The coordinates of ``sweep.nc`` (those of the sets' statistics included; see :meth:`datasets`)."""
        coords = {"protrusion": coordinate("protrusion", self.prot),
                  "roughness": coordinate("roughness", self.labels), "damping": coordinate("damping", self.damp)}
        if self.stepping:
            coords["direction"] = coordinate("direction", np.array(DIRECTIONS))
        if self.n_real > 1:
            coords["realisation"] = ENSEMBLE["realisation"].data(np.arange(self.n_real), ("realisation",))
        coords.update(roughness_coordinates([statistics[label] for label in self.labels]))
        coords.update(power_coordinates(self.scene, self.prot))
        return coords

    def _attrs(self, k_source: str, attrs: dict, statistics: dict[str, dict[str, Any]]) -> dict[str, Any]:
        """The global attributes of both datasets (see :meth:`datasets`)."""
        sets = roughness_sets(self.scene)
        # one attribute for all sets: a label made from the values has '.', which CF's attribute names exclude
        out = {"roughness_sets": json.dumps({label: roughness_record(sets[label], statistics[label])
                                             for label in self.labels}, default=str)}
        out.update(attrs)
        out["k_source"] = k_source
        own = scene_label(self.scene)
        if own in self.labels:  # (the report's default slice: the scene's own roughness)
            out["scene_roughness"] = own
        return out

    def histories(self, k_source: str, attrs: dict, run: dict[str, xr.Variable] | None = None, *,
                  statistics: dict[str, dict[str, Any]]) -> xr.Dataset | None:
        """``sweep_histories.nc`` from the parts added (arguments: :meth:`datasets`; ``None``: no part kept
        histories). Made once: the same object until a part with histories is added, so that the sweep can
        have it written while the other batches run (:meth:`pipeline.runner.Inputs.write_early`) and return
        it with ``sweep.nc``."""
        if not self.hist:
            return None
        if self._histories is None:
            hc = {name: c for name, c in self._coords(statistics).items() if name != "realisation"}  # (realisation 0)
            hc["protrusion"] = coordinate("protrusion", self.hist_prot)
            hc.update(power_coordinates(self.scene, self.hist_prot))
            hc[TIME] = coordinate(TIME, self.time)
            hds = xr.Dataset({name: HISTORIES[name].data(a, ("protrusion", "roughness", "damping", TIME))
                              for name, a in self._ordered(self.hist, "h_").items()}, coords=hc).assign(run or {})
            hds.attrs.update(self._attrs(k_source, attrs, statistics))
            self._histories = hds
        return self._histories


def roughness_coordinates(statistics: list[dict[str, Any]]) -> dict[str, xr.Variable]:
    """``roughness_sigma`` [nm], ``roughness_summit_radius`` [um], ``roughness_summit_density`` [um^-2] and
    ``roughness_plasticity_index`` [1] of each roughness set, from the statistics its interface model used
    (:func:`pipeline.model.interface_tables.used_statistics`, in the order of the ``roughness`` dimension):
    the given keys of explicit statistics, the scans' of an AFM set."""
    return {name: COORDINATES[name].data([float(st[key]) for st in statistics], ("roughness",))
            for name, key in ROUGHNESS_COORDINATES.items()}


#: The coordinates along ``roughness`` and the statistics (:func:`pipeline.model.interface_tables.used_statistics`)
#: they hold.
ROUGHNESS_COORDINATES = {"roughness_sigma": "sigma_nm", "roughness_summit_radius": "summit_radius_um",
                         "roughness_summit_density": "summit_density_per_um2",
                         "roughness_plasticity_index": "plasticity_index"}
