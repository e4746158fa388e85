"""Analyses: what the pipeline concludes from in-memory results (datasets, strings), with no file I/O.

Layer between the model and the stages (``config -> physics -> model -> analyses -> stages -> cli``):
modules here import from the physics, the variable schema and each other, never from
:mod:`pipeline.stages` or the runner. A stage loads its inputs, calls an analysis and writes what it
returns.

* :mod:`.sweep_slices`: the roughness x damping slices of a sweep, first contact, dataset accessors;
* :mod:`.report_settings`: the scene keys the report reads, as one frozen record;
* :mod:`.report_tables`: ``summary.csv`` and ``summary.md``;
* :mod:`.report_figures`: which report figures to draw from which data (drawing: :mod:`pipeline.analyses.plots`);
* :mod:`.paper_comparison`: ``comparison.md``, our numbers against :mod:`pipeline.physics.paper`;
* :mod:`.narrative`: the generated observations and the generated section of docs/results.md;
* :mod:`.ensemble`: the statistics that judge a paper target over DMW realisations (touchdown
  probability and its 0.5 crossing, medians and 10-90 % ranges, mean ± std, exceedance probability);
* :mod:`.ensemble_comparison`: the comparison's column and section over the realisations (formatting);
* :mod:`.markdown`: numbers and tables as Markdown text;
* :mod:`.accuracy`: the accuracy-knob study (error and cost of each knob, chosen defaults);
* :mod:`.study`: the parameter studies' free parameters, candidates and targets (the interpretation of
  the declarations of :data:`pipeline.physics.paper.TARGETS`), residuals and headline outputs;
* :mod:`.identification`: differential evolution, profiles and correlation of ``hdi identify``;
* :mod:`.screening`: Morris and Sobol indices of ``hdi sensitivity``.
"""
