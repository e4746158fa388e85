"""The pipeline's stages: each module declares ``STAGE = pipeline.runner.Stage(...)``.

:mod:`pipeline.runner` discovers the declarations (no list to edit: a new module with a ``STAGE``
is a new ``hdi`` stage), hashes each stage's declared inputs by content, recomputes what is stale and
writes the outputs atomically. A stage is made current through the runner, never through its module:
``pipeline.runner.ensure(name, scene, out, **options)`` returns its primary output (the options, such as
``force``, ``scheduler``, ``workers`` or a test's ``task``, go to :class:`pipeline.runner.Runner`), and
:func:`pipeline.api.run_stage` is the users' form (a scene file, the command line's option checks).
"""
