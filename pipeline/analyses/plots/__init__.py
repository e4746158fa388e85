"""Figures of the report stage (matplotlib object API: no pyplot, no global state).

Every ``fig_*`` function takes datasets as written by the stages (dataset units, see docs/datasets.md), draws
one figure, writes it as PNG with :func:`save` and returns the path. The panels a notebook draws on its
own axes are ``plot_*`` functions: each takes ``ax=`` (a matplotlib ``Axes``; ``None``: a new figure's)
and returns the axes it drew on; the ``fig_*`` figures are made of them. Figures are
:class:`matplotlib.figure.Figure` objects that are never registered with pyplot, so nothing leaks
between calls and nothing needs a display (``MPLBACKEND=Agg`` or not).

Conventions: every axis is labelled ``quantity [units]`` (:func:`axis_label`, units taken from the
variable's ``units`` attribute and written in plain text: ``um2`` -> ``µm²``); every title says what
is shown and for which scene (:func:`title`); regimes use :data:`REGIME_COLOURS`.

The figures are grouped by family, one module each; this package holds every public name of them, so
``plots.fig_fhm`` and ``from pipeline.analyses.plots import plot_fhm`` name the same function:

* :mod:`.common`: colours, axis labels with units, titles, new figures and panels, shading, :func:`save`;
* :mod:`.pool`: drawing independent figures at once in forked processes (:func:`draw_all`);
* :mod:`.paper`: the paper's Figs. 3-7 (clearance, forces, stresses, FHM, shear) and the calibration;
* :mod:`.ensemble`: touchdown probability and FHM spread over DMW realisations, the bouncing band;
* :mod:`.inputs`: roughness statistics, the DMW record, the interface models, the bulge lift table;
* :mod:`.statics`: the statics map (static states with their stability, barriers);
* :mod:`.accuracy`: the solver's work-precision figure.
"""

from __future__ import annotations

from .common import (REGIME_COLOURS, DPI, LINE_COLOURS, unit_text, axis_label, var_label, DRAWING_MODULES, title,
                     new_figure, panel, heater_power_axis, envelope, save, note, shade_regimes, runs)
from .pool import draw_all
from .paper import (fig_clearance, plot_clearance, FORCES, fig_forces, plot_forces, STRESSES, fig_stresses, fig_fhm,
                    plot_fhm, fig_shear, fig_calibration)
from .ensemble import (touchdown_lines, fig_ensemble, plot_touchdown_probability, plot_ensemble_fhm, fig_band,
                       plot_band, plot_band_probabilities)
from .inputs import (fig_bulge, ROUGH_BARS, ROUGH_TABLE, has_afm_surfaces, fig_roughness, fig_dmw, LIGHT_CONTACT_AREA,
                     fig_interface_models)
from .statics import plot_statics_states, plot_statics_barriers, fig_statics
from .accuracy import fig_work_precision

__all__ = ["REGIME_COLOURS", "DPI", "LINE_COLOURS", "unit_text", "axis_label", "var_label", "DRAWING_MODULES",
           "title", "new_figure", "panel", "heater_power_axis", "envelope", "save", "note", "shade_regimes", "runs",
           "draw_all", "fig_clearance", "plot_clearance", "FORCES", "fig_forces", "plot_forces", "STRESSES",
           "fig_stresses", "fig_fhm", "plot_fhm", "fig_shear", "fig_calibration", "touchdown_lines", "fig_ensemble",
           "plot_touchdown_probability", "plot_ensemble_fhm", "fig_band", "plot_band", "plot_band_probabilities",
           "fig_bulge", "ROUGH_BARS", "ROUGH_TABLE", "has_afm_surfaces", "fig_roughness", "fig_dmw",
           "LIGHT_CONTACT_AREA", "fig_interface_models", "plot_statics_states", "plot_statics_barriers",
           "fig_statics", "fig_work_precision"]
