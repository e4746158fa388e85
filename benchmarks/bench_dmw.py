"""Benchmarks of the DMW stage's physics (pipeline.physics.microwaviness).

Target (task brief): synthesising the paper scene's record, 2 ms at 4 MS/s (8000 samples), in well
under 0.1 s. Also timed: the LDV processing of the same record (velocity to displacement) and its
periodogram, for reference.
"""

from __future__ import annotations

from benchmarks.common import record, timeit
from pipeline.physics import microwaviness as dmw

FS = 4e6            # [Hz]
BAND = (1e4, 5e5)   # [Hz]
DURATION = 2e-3     # [s]


def run(results: list[dict]) -> None:
    """Append the DMW benchmark rows to ``results``."""
    def synth() -> None:
        dmw.synthesize(0.5, BAND, -2.0, DURATION, FS, seed=20090601)

    record(results, "dmw.synthesize 2 ms @ 4 MS/s (8000 samples)", timeit(synth, repeat=21),
           target_s=0.1, samples=int(DURATION * FS))
    x = dmw.synthesize(0.5, BAND, -2.0, DURATION, FS, seed=20090601)
    v = dmw.displacement_to_velocity(x, FS)
    record(results, "dmw.velocity_to_displacement 2 ms @ 4 MS/s",
           timeit(lambda: dmw.velocity_to_displacement(v, FS, *BAND), repeat=21))
    record(results, "dmw.spectrum (periodogram) 2 ms @ 4 MS/s", timeit(lambda: dmw.spectrum(x, FS), repeat=21))
    long_s = 60.0 / 5425.0  # one revolution at 5425 rpm [s]
    record(results, "dmw.synthesize one revolution (11.06 ms) @ 4 MS/s",
           timeit(lambda: dmw.synthesize(0.5, BAND, -2.0, long_s, FS, seed=1), repeat=11), target_s=0.1)
