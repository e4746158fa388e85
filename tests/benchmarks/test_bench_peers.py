"""The peer rows of the bench (benchmarks/bench_peers.py) with fake peers: a peer that agrees is timed beside the
kernel in the same rounds and carries ``speedup_of_kernel``; one that disagrees is void (a row with the numbers,
never timed); one that could not be installed has a row saying why; every row names its peer and scene."""

from __future__ import annotations

import time

import pytest

from bench_fakes import use_fake_load
from benchmarks import bench_peers

KERNEL_RUN = {"fhm_bv": 12.2135, "clearance": 5.03023e-9}


def busy(seconds: float) -> None:
    """Spin this thread's CPU for ``seconds`` (a contender whose thread time is known)."""
    t0 = time.thread_time()
    while time.thread_time() - t0 < seconds:
        pass


class FakePeer:
    """A peer whose run gives ``result`` and whose call spins ``seconds``; counts its timed calls."""

    def __init__(self, result: dict, seconds: float) -> None:
        self.result, self.seconds, self.calls = result, seconds, 0

    def run(self) -> dict:
        return dict(self.result)

    def call(self) -> None:
        self.calls += 1
        busy(self.seconds)


def test_rows_of_one_scene(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    use_fake_load(monkeypatch, [0.3] * 10)
    agreeing = FakePeer({"ok": True, "fhm_bv": 12.16, "clearance": 5.03025e-9, "rhs_evaluations": 32830}, 0.004)
    void = FakePeer({"ok": True, "fhm_bv": 12.6, "clearance": 5.03025e-9, "rhs_evaluations": 20000}, 0.001)
    results: list[dict] = []
    bench_peers.compare(results, "flying", 5.0, lambda: busy(0.002), KERNEL_RUN,
                        {"DOP853": agreeing, "LSODA": void, "CVODE": "not installed: no module named 'cvode'"},
                        rounds=9, kernel_extra={"rhs_evaluations": 24865})
    names = [r["name"] for r in results]
    assert names == [bench_peers.KERNEL.format(label="flying", prot=5.0)] + [
        bench_peers.PEER.format(peer=p, label="flying", prot=5.0) for p in ("DOP853", "LSODA", "CVODE")]
    assert names[1] == ("peers: numbalsoda DOP853 (numba cfunc RHS), flying 5 nm (speedup_of_kernel = peer / "
                        "kernel)")
    kernel, dop, lsoda, cvode = results
    assert kernel["n"] == 9 and kernel["rhs_evaluations"] == 24865 and kernel["fhm_bv"] == 12.2135
    # the agreeing peer: timed in the same 9 rounds; its speed-up is its median over the kernel's (4 ms / 2 ms)
    assert agreeing.calls == 9 and dop["n"] == 9
    assert dop["speedup_of_kernel"] == dop["median_s"] / kernel["median_s"] == pytest.approx(2.0, rel=0.25)
    assert dop["kernel_median_s"] == kernel["median_s"]
    assert (dop["peer"], dop["scene"], dop["agrees"], dop["rhs_evaluations"]) == ("DOP853", "flying", True, 32830)
    # tol: the same division and subtraction as the row's, in another order of operations (abs): a few ulps
    assert dop["fhm_bv_rel_diff"] == pytest.approx(abs(12.16 / 12.2135 - 1), rel=1e-12)
    # the disagreeing peer: never timed, a row with its numbers
    assert void.calls == 0 and lsoda["void"] is True and "median_s" not in lsoda
    assert lsoda["failed"].startswith("void: disagrees with the kernel: FHM/BV 12.6 % against 12.2135 % (3.165%")
    # tol: the row's division and subtraction: a few ulps
    assert lsoda["fhm_bv_rel_diff"] == pytest.approx(12.6 / 12.2135 - 1, rel=1e-12) and lsoda["peer"] == "LSODA"
    # the missing peer: a row saying why, with the load like every row
    assert cvode["failed"] == "not installed: no module named 'cvode'" and cvode["peer_installed"] is False
    assert all("load_start" in r and r["scene"] == "flying" for r in results[1:])
    assert "FAILED: void" in capsys.readouterr().out
