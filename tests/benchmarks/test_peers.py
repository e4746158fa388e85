"""The bench's peers (benchmarks/peers.py), without numbalsoda: the cfunc right-hand side is the naive baseline's
physics, a peer on the scaled state with ``atol = 1`` steps the same problem at the same tolerances (an
integrator of numbalsoda's interface made of scipy's DOP853 agrees with the kernel within the bench's limits),
the agreement check, the alternated CPU timings and the rows' reason when numbalsoda is missing."""

from __future__ import annotations

import ctypes

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from benchmarks import naive, peers
from pipeline.config.scene import load_scene
from pipeline.model import assembly, outcomes, running
from pipeline.stages.simulate import model_inputs

K = 0.445


@pytest.fixture(scope="module")
def setup(tmp_path_factory, paper_config):
    scene = load_scene(paper_config, ["solver.duration_ms=1.0", "solver.transient_ms=0.4", f"contact.k={K}"])
    interface, record = model_inputs(scene, tmp_path_factory.mktemp("peers"))
    return scene, interface, record, assembly.build_model(scene, interface, record, K)


@pytest.mark.parametrize("protrusion", [5.0, 11.0])
def test_the_cfunc_rhs_is_the_naive_rhs(setup, protrusion):
    """At states around the start, in contact and out of it, the scaled compiled RHS (directly and through its C
    address, as numbalsoda calls it) gives the naive baseline's derivatives times 1 / scale, and counts its calls."""
    scene, interface, record, model = setup
    ph = naive.physics(scene, interface, record, K, protrusion)
    rhs = naive.right_hand_side(ph, [0])
    scale = model.atol[:4]
    data = peers.pack(ph, scale)
    y0, _ = running.start(model, protrusion * 1e-9)
    c_rhs = ctypes.CFUNCTYPE(None, ctypes.c_double, *[ctypes.POINTER(ctypes.c_double)] * 3)(peers.rhs_address())
    rng = np.random.default_rng(1)
    modes = set()
    for i in range(12):
        y = y0 + rng.normal(size=4) * scale * 1e3
        t = rng.uniform(0.0, model.duration)
        contact = bool(ph.d_nom + y[0] - ph.lc * y[1] - ph.disk(t)[0] < ph.ksig)
        modes.add(contact)
        expected = np.array(rhs(t, y, contact)) / scale
        du = np.zeros(4)
        peers.rhs_core(t, y / scale, du, data)
        # tol: the same operations but np.interp's table lookup (the table's own x against x0 + i dx) and the
        # scaling's two roundings: a few ulps of each term
        assert du == pytest.approx(expected, rel=1e-12, abs=1e-12 * np.max(np.abs(expected))), i
        u, du_c = np.ascontiguousarray(y / scale), np.zeros(4)
        ptr = ctypes.POINTER(ctypes.c_double)
        c_rhs(t, u.ctypes.data_as(ptr), du_c.ctypes.data_as(ptr), data.ctypes.data_as(ptr))
        assert np.array_equal(du_c, du)
    assert modes == ({False} if protrusion < 7 else {True})  # (flying out of contact, sliding in it)
    assert data[peers.COUNT] == 24


def test_pack_refuses_what_the_peers_do_not_interpolate(setup):
    scene, interface, record, model = setup
    linear = naive.physics(scene, interface, record, K, 5.0, dmw_interpolation="linear")
    with pytest.raises(ValueError, match="cubic spline; got 'linear'"):
        peers.pack(linear, model.atol[:4])
    ph = naive.physics(scene, interface, record, K, 5.0)
    ph.x = ph.x.copy()
    ph.x[3] += 0.4 * (ph.x[1] - ph.x[0])
    with pytest.raises(ValueError, match="uniform separation grid"):
        peers.pack(ph, model.atol[:4])
    with pytest.raises(ValueError, match="four-component state; scale has 5"):
        peers.pack(naive.physics(scene, interface, record, K, 5.0), np.ones(5))


def scipy_dop853(funcptr, u0, t_eval, data, rtol, atol, mxstep):
    """An integrator of numbalsoda's interface (the RHS from ``data``, not from ``funcptr``): scipy's DOP853."""
    def f(t, u):
        du = np.empty(4)
        peers.rhs_core(t, u, du, data)
        return du
    sol = solve_ivp(f, (t_eval[0], t_eval[-1]), u0, method="DOP853", t_eval=t_eval, rtol=rtol, atol=atol)
    return sol.y.T, sol.success


@pytest.mark.parametrize("protrusion", [5.0, 11.0])
def test_a_peer_of_numbalsodas_interface_agrees_with_the_kernel(setup, protrusion):
    """A Dormand-Prince 8(5,3) integrator on the scaled state with atol = 1 from the project's start, sampled at
    the kernel's output grid, agrees with the kernel within the bench's limits (and a BV 2 % off would not)."""
    scene, interface, record, model = setup
    ph = naive.physics(scene, interface, record, K, protrusion)
    y0, _ = running.start(model, protrusion * 1e-9)
    kernel = outcomes.summarize(running.run_model(model, protrusion * 1e-9))
    peer = peers.Peer("scipy DOP853", scipy_dop853, ph, y0)
    res = peer.run()
    assert res["ok"] and res["rhs_evaluations"] > 1000
    assert peer.t_eval.size == int(round(model.duration / model.output_step)) + 1  # (the kernel's output grid)
    verdict = peers.agreement(res, kernel)
    assert verdict["agrees"], verdict
    assert res["regime"] == kernel["regime"]
    off = dict(res, fhm_bv=res["fhm_bv"] * 1.02)
    assert not peers.agreement(off, kernel)["agrees"]


def test_agreement_limits_and_reasons():
    kernel = {"fhm_bv": 0.335, "clearance": -0.6086e-9}
    same = peers.agreement({"ok": True, "fhm_bv": 0.335 * 1.0099, "clearance": -0.6086e-9 * 1.00099}, kernel)
    assert same["agrees"] and "why" not in same
    # tol: 0.335 * 1.0099 / 0.335 - 1 is 0.0099 up to the two roundings of the product and quotient (~1e-14)
    assert same["fhm_bv_rel_diff"] == pytest.approx(0.0099, rel=1e-9)
    bv = peers.agreement({"ok": True, "fhm_bv": 0.343896, "clearance": -0.608212e-9}, kernel)
    assert not bv["agrees"]
    assert bv["why"].startswith("disagrees with the kernel: FHM/BV 0.343896 % against 0.335 % (2.656%, limit 1.0%)")
    clr = peers.agreement({"ok": True, "fhm_bv": 0.335, "clearance": -0.6086e-9 * 1.0011}, kernel)
    assert not clr["agrees"] and "(0.110%, limit 0.1%)" in clr["why"]
    failed = peers.agreement({"ok": False, "rhs_evaluations": 10}, kernel)
    assert not failed["agrees"] and "integrator failed" in failed["why"]


def test_alternate_rotates_the_order_and_times_each_call():
    """Each round calls every contender once, the order rotated; each time is the clock's difference over the call."""
    calls: list[str] = []
    ticks = iter(range(1000))
    clock = lambda: float(next(ticks))  # noqa: E731 (each read one tick later)
    got = peers.alternate({n: (lambda n=n: calls.append(n)) for n in "abc"}, rounds=4, clock=clock)
    assert calls == list("abc" "bca" "cab" "abc")
    assert got == {n: [1.0] * 4 for n in "abc"}
    assert peers.speedup_of_kernel([3.0, 9.0, 6.0], [2.0, 1.0, 4.0]) == 3.0


def test_without_numbalsoda_each_peer_says_why_and_how_to_get_it():
    def missing(name):
        raise ModuleNotFoundError(f"No module named '{name}'")

    got = peers.load_peers(missing)
    assert list(got) == list(peers.METHODS)
    for why in got.values():
        assert why.startswith("not installed: numbalsoda could not be imported (ModuleNotFoundError: No module named "
                              "'numbalsoda')")
        assert "gfortran" in why and "`make bench-peers-setup`" in why

    class Lib:
        dop853, lsoda = object(), object()

    found = peers.load_peers(lambda name: Lib)
    assert found == {"DOP853": Lib.dop853, "LSODA": Lib.lsoda, "LSODA at tolerances / 10": Lib.lsoda}
