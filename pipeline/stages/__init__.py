"""The pipeline's stages: each module declares ``STAGE = pipeline.runner.Stage(...)``.

:mod:`pipeline.runner` discovers the declarations (no list to edit: a new module with a ``STAGE``
is a new ``hdi`` stage), hashes each stage's declared inputs by content, recomputes what is stale and
writes the outputs atomically. Each module keeps ``run(scene, out, **options)`` as a shorthand for
``pipeline.runner.build(stage, scene, out, **options)``.
"""
