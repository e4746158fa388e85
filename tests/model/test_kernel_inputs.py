"""The caching rule of the kernel's per-protrusion inputs (pipeline.model.kernel_inputs): one rule for
every cache, made on the first ask, at most its size, the oldest dropped first, permanent entries kept."""

from __future__ import annotations

from pipeline.model import kernel_inputs as ki


def test_a_cache_makes_an_entry_once_and_drops_the_oldest_past_its_size():
    cache: dict = {}
    made: list = []

    def ask(key):
        return ki._cached(cache, key, 3, lambda: made.append(key) or f"table {key}")

    assert [ask(k) for k in (1.0, 2.0, 1.0)] == ["table 1.0", "table 2.0", "table 1.0"]
    assert made == [1.0, 2.0]  # the second ask of 1.0 read the cache
    for k in (3.0, 4.0, 5.0):
        ask(k)
    assert list(cache) == [3.0, 4.0, 5.0] and made == [1.0, 2.0, 3.0, 4.0, 5.0]
    ask(1.0)  # dropped before: made anew
    assert made[-1] == 1.0 and list(cache) == [4.0, 5.0, 1.0]


def test_a_permanent_entry_is_never_dropped():
    cache: dict = {"capped_area": "cap"}
    for k in range(10):
        ki._cached(cache, (float(k), 1.0), ki.INTEGRATED_CACHE, lambda: "tables")
    assert cache["capped_area"] == "cap" and len(cache) == ki.INTEGRATED_CACHE
    assert list(cache)[1:] == [(float(k), 1.0) for k in range(10 - ki.INTEGRATED_CACHE + 1, 10)]
