"""The slider's forces and the right-hand side of its equations of motion (numba, inlined into the kernel).

Equations of motion (docs/model.md, section "Slider dynamics"), state ``y = (z, theta, z', theta')``
(:mod:`pipeline.model.state`) in SI units::

    m z''     = F_f + F_r + F_i
    I theta'' = l_f F_f - l_r F_r - l_c F_i - friction_arm Q

* front pad (``l_f`` ahead of the CG), linear:   ``F_f = -k_f (z + l_f theta - w_f) - c_f (...)'``
* rear pad (``l_r`` behind): the scene's rear law (``air_bearing.rear_law``, :func:`call_rear_law`) on the
  rear gap ``g_r = g0 + z - l_r theta - w_r``, minus the damper ``c_r g_r'``
* interface at the TFC point (``l_c`` behind), gap ``g = FH0 - delta + z - l_c theta - w_c`` to the mean
  of surface heights and ISBL separation ``d = g - y_s`` to the mean of summit heights (docs/model.md,
  section "Separation datum"): ``F_i = -A_n p_a(d)`` always (adhesion effect), plus
  ``A_n p_c(d) - c_c d'`` while in contact (``d < k sigma``, the paper's criterion)
* friction ``Q = A_n tau(d)`` in contact, along the disk's motion (leading to trailing edge) at the
  air-bearing surface; its moment about the CG is ``-friction_arm Q`` (it pitches the leading edge down).
  With ``contact.friction_switching = "continuous"`` (docs/model.md, section "Switched and continuous
  friction") the friction table holds two tables side by side (8 columns): the solid friction stress
  (columns 0-3), in contact as above, and the lubricant shear ``tau_lub a_w(d)`` (4-7), at every ``d``.
* the disk under each point moves with the DMW ``w(t)`` delayed by the disk's travel time.
* an air-bearing force at the TFC point (docs/model.md, section "Model variants"): the closed-form
  gap-power stiffening spring ``F_t = k_t [G(g_n) - G(g)]``, stiffness ``-dF_t/dg = k_t [(g0/g)^p - 1]``
  (``Variants.gap_power``, :func:`pipeline.physics.tfc_laws.tfc_stiffening_force`), or any law
  tabulated versus the gap (``Tables.tfc``, :func:`pipeline.model.kernel_inputs.tfc_table`), or both.

The closed-form laws are compiled from their one definition in :mod:`pipeline.physics.air_bearing`.

The kernel's inputs (its slots: :data:`pipeline.model.dynamics.SLOTS`) are arguments of these
functions one by one, each ``None`` when its effect is off: numba compiles one kernel per combination
and prunes the branches of the effects that are off (``if x is None``) at compile time. The inlined
helpers take the state's components as scalars (an array handed to an inlined helper costs a
reference-count pair per call, see :func:`pipeline.model.dynamics._integrate`).

Rear laws. A rear law's ``force`` (:class:`pipeline.physics.air_bearing.RearLaw`) is a function of
numbers; the kernel receives the law as a :class:`RearLawRef` (:func:`rear_law_ref`), whose numba type
names the law, so numba compiles one kernel per law with the law's function inlined and caches it on
disk like the other slots' specialisations (a numba dispatcher passed as an argument instead would
not be found in the on-disk cache by the next process: measured with numba 0.68.1).
"""

from __future__ import annotations

import hashlib
import warnings
from typing import Any

from numba import njit, types
from numba.core.errors import NumbaError, NumbaWarning
from numba.extending import NativeValue, models, overload, register_model, typeof_impl, unbox

from ..physics import air_bearing as ab
from ..physics import tfc_laws
from .compiled import BORROWING, kernel_jit
from .piecewise import _ppat, _ppat_at, _ppindex, _ppslope_at, _ppval, disk, disk3
from .state import MENISCUS, THETA, THETA_RATE, Z, Z_RATE

_jit = kernel_jit(__name__)
_inline = kernel_jit(__name__, inline="always")
_jit_borrowing = kernel_jit(__name__, **BORROWING)  # (no reference counts: pipeline.model.compiled.BORROWING)

# the air-bearing laws at the TFC point, compiled from their one definition in pipeline.physics.air_bearing
_stiffening_potential = _inline(tfc_laws.stiffening_potential)
_stiffening_stiffness = _inline(tfc_laws.stiffening_stiffness)


# ---------------------------------------------------------------------------------------------
# the rear law, by name

class RearLawRef:
    """The rear law a kernel runs with, by its name in :data:`pipeline.physics.air_bearing.REAR_LAWS`
    (made by :func:`rear_law_ref`, which checks that the law compiles). ``key``: a digest of the law's
    code, part of its numba type, so an edited law (a test's, outside the package's code key) is not
    read from the on-disk cache of another."""

    __slots__ = ("name", "key", "numba_type")

    def __init__(self, name: str, key: str):
        self.name, self.key = name, key
        self.numba_type = RearLawType(name, key)  # (made once: numba types the argument at every call)

    def __reduce__(self):
        return RearLawRef, (self.name, self.key)

    def __repr__(self) -> str:
        return f"RearLawRef({self.name!r})"


class RearLawType(types.Type):
    """numba type of a :class:`RearLawRef`: one per law (its name and code digest), no run-time data."""

    def __init__(self, name: str, key: str):
        self.law, self.code = name, key
        super().__init__(name=f"RearLaw({name}, {key})")


@typeof_impl.register(RearLawRef)
def _typeof_rear_law(val: RearLawRef, c: Any) -> RearLawType:
    return val.numba_type


register_model(RearLawType)(models.OpaqueModel)


@unbox(RearLawType)
def _unbox_rear_law(typ: RearLawType, obj: Any, c: Any) -> NativeValue:
    return NativeValue(c.context.get_dummy_value())  # (the type says everything)


def _law_key(law: ab.RearLaw) -> str:
    """Digest of a rear law's compiled code (bytecode, constants, names) and its ``min_gap``."""
    code = law.force.__code__
    text = repr((code.co_code, code.co_consts, code.co_names, law.min_gap))
    return hashlib.sha256(text.encode()).hexdigest()[:12]


_CHECKED: dict[tuple[str, Any], RearLawRef] = {}


def rear_law_ref(name: str) -> RearLawRef:
    """The kernel's handle of the rear law ``name`` (``air_bearing.rear_law``), once its force is found
    to compile as a function of five floats (checked once per law and process).

    Raises
    ------
    ValueError
        One line, for a name not in the registry or a law without a compiled form.
    """
    law = ab.REAR_LAWS.lookup(name)
    found = _CHECKED.get((name, law))
    if found is not None:
        return found
    if not callable(law.force) or not hasattr(law.force, "__code__"):
        raise ValueError(f"air_bearing.rear_law = {name!r}: the law has no compiled form (its force must be a "
                         "Python function of the numbers g, g0, n, F0, k_r: pipeline.physics.air_bearing.RearLaw)")
    try:  # (cached on disk like the kernel: a fresh process loads the check instead of compiling it)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NumbaWarning)  # (a law numba cannot cache is still checked)
            kernel_jit(__name__)(law.force).compile((types.float64,) * 5)
    except (NumbaError, TypeError, ValueError) as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ValueError(f"air_bearing.rear_law = {name!r}: its force does not compile for the kernel "
                         f"(a function of the numbers g, g0, n, F0, k_r: {first})") from None
    found = _CHECKED[(name, law)] = RearLawRef(name, _law_key(law))
    return found


def call_rear_law(law, g, g0, n, F0, k_r):
    """The rear law ``law`` (a :class:`RearLawRef`) at the rear gap ``g`` [m]: its force [N] (compiled
    code only, :func:`_rear_law_impl`)."""
    raise NotImplementedError("call_rear_law is called from compiled code only")


@overload(call_rear_law, inline="always", jit_options=dict(error_model="numpy"))
def _rear_law_impl(law, g, g0, n, F0, k_r):
    """The compiled :func:`call_rear_law`: the registry's force of the law its type names, inlined; clamped
    at ``min_gap g0`` when the law has one (:class:`pipeline.physics.air_bearing.RearLaw`)."""
    if not isinstance(law, RearLawType):
        return None
    entry = ab.REAR_LAWS[law.law]
    force = njit(inline="always", error_model="numpy")(entry.force)
    if entry.min_gap is None:
        def impl(law, g, g0, n, F0, k_r):
            return force(g, g0, n, F0, k_r)
    else:
        lo = float(entry.min_gap)

        def impl(law, g, g0, n, F0, k_r):
            return force(max(g, lo * g0), g0, n, F0, k_r)
    return impl


# ---------------------------------------------------------------------------------------------
# gaps, separation, disk

@_jit
def gap_at(p, z, theta, w):
    """Gap [m] at the TFC point to the mean of the disk's surface heights, ``FH0 - delta + z - l_c theta - w``.

    ``FH0`` is measured to the mean of surface heights (docs/model.md, section "Separation datum");
    scalars or arrays of ``z`` [m], ``theta`` [rad], ``w`` [m] alike (the one home of the datum, for
    the kernel and post-processing).
    """
    return p.FH0 - p.delta + z - p.l_c * theta - w


@_jit
def separation_at(p, z, theta, w):
    """ISBL separation ``d`` [m] to the mean of summit heights: :func:`gap_at` minus ``y_s = p.y_s``.

    ``d = FH0 - delta + z - l_c theta - w - y_s`` (docs/model.md, section "Separation datum"; the ISBL
    tables are functions of this d).
    """
    return gap_at(p, z, theta, w) - p.y_s


@_jit_borrowing
def separation(p, dmw, t, y):
    """TFC separation ``d`` [m] and its rate [m/s] (docs/model.md, section "Separation datum").

    Compiled once, on its own and without reference counts (:data:`pipeline.model.compiled.BORROWING`: it
    reads ``y`` and allocates nothing), and called from the kernel's loop itself, never from an inlined
    helper: inlined, it was compiled again at each of its four call sites (docs/kernel.md, section "Compile
    time"). The state is read before the DMW lookup's branches.
    """
    z, theta, vz, vtheta = y[Z], y[THETA], y[Z_RATE], y[THETA_RATE]
    wc, vc = disk(p, dmw, t)
    return separation_of(p, z, theta, vz, vtheta, wc, vc)


@_inline
def separation_of(p, z, theta, vz, vtheta, wc, vc):
    """TFC separation ``d`` [m] and its rate [m/s] at the state ``(z, theta, vz, vtheta)`` [m, rad, m/s, rad/s]
    over the disk at ``wc`` [m] moving at ``vc`` [m/s] (:func:`separation` with the disk looked up: the kernel
    reuses the step's lookup at the step's end)."""
    return separation_at(p, z, theta, wc), vz - p.l_c * vtheta - vc


# ---------------------------------------------------------------------------------------------
# forces

@_inline
def _stiffening(q, g):
    """Force [N] (up positive) and stiffness [N/m] of the gap-power stiffening spring at the gap ``g`` [m].

    ``k(g) = k_t [(g0/g)^q - 1]``, force its integral from the nominal gap (constant ``q.f0`` =
    ``G(g_n)``), continued linearly below ``q.g_min`` where the law is singular (``q``: a
    :data:`pipeline.model.dynamics.GAP_POWER` record).
    """
    gm = q.g_min
    gg = max(g, gm)
    f = q.k_t * (q.f0 - _stiffening_potential(gg, q.g0, q.q))
    if g < gm:
        return f + q.k_min * (gm - g), q.k_min
    return f, _stiffening_stiffness(gg, q.g0, q.k_t, q.q)


@_inline
def _rear_force(p, rear_law, z, theta, vz, vtheta, wr, vr):
    """Rear-pad force [N] (up positive): the scene's rear law (:func:`call_rear_law`) plus its damper."""
    g_r = p.g0 + z - p.l_r * theta - wr
    F_r = call_rear_law(rear_law, g_r, p.g0, p.n, p.F_r0, p.k_r)
    F_r -= p.c_r * (vz - p.l_r * vtheta - vr)
    return F_r


@_inline
def tfc_air_force(p, gap_power, tfc, g):
    """Air-bearing force [N] (up positive) and stiffness ``-dF/dg`` [N/m] at the TFC point, gap ``g`` [m]:
    the closed-form gap-power law plus the tabulated law (each ``None`` when off; zero without both)."""
    F = 0.0
    k = 0.0
    if gap_power is not None:
        f, kg = _stiffening(gap_power, g)
        F += f
        k += kg
    if tfc is not None:
        f, slope = _ppval(tfc, p.tfc_x0, p.tfc_h, g)
        F += f
        k -= slope
    return F, k


@_inline
def _interface_force(p, contact, adhesion, friction, meniscus, F_i, z, theta, vz, vtheta, q, wc, vc, in_contact):
    """Add the interface forces at the state (disk under the TFC point at ``wc`` [m], ``vc`` [m/s]) to
    ``F_i`` [N]: adhesion always, contact pressure and damper in contact; returns it, the friction
    force ``Q`` [N] and the rate ``dq/dt`` [Pa/s] of the meniscus state (0 without one).

    Friction: the table's (first) stress in contact; a second table beside it (8 columns: the
    continuous lubricant shear, docs/model.md, section "Switched and continuous friction") acts in
    either mode, continuous in ``d`` as the wetted area is.

    With a meniscus formation time ``meniscus`` [s] the adhesion pressure is the state ``q`` [Pa],
    relaxing towards the table's ``p_a(d)``: ``dq/dt = (p_a(d) - q) / meniscus`` (docs/model.md,
    section "Meniscus formation").
    """
    Q = 0.0
    dq = 0.0
    if adhesion is not None or contact is not None:
        d, dd = separation_at(p, z, theta, wc), vz - p.l_c * vtheta - vc  # (:func:`separation`)
        # one index for every table (they share the separation grid)
        i, s = _ppindex(p.tab_n, p.tab_x0, p.tab_h, d)
        if adhesion is not None:
            if meniscus is not None:
                F_i -= p.A_n * q
                dq = (_ppat(adhesion, i, s) - q) / meniscus
                if adhesion.shape[1] == 8:  # the part that acts at once (two populations: the bridges)
                    F_i -= p.A_n * _ppat_at(adhesion, i, s, 4)
            else:
                F_i -= p.A_n * _ppat(adhesion, i, s)
        if contact is not None:
            if in_contact:
                F_i += p.A_n * max(_ppat(contact, i, s), 0.0) - p.c_c * dd
            if friction is not None:
                Q = friction_force(p, friction, in_contact, i, s)
    return F_i, Q, dq


@_inline
def friction_force(p, friction, in_contact, i, s):
    """The friction force ``Q`` [N] at the piece ``i`` and offset ``s`` of the separation grid
    (:func:`pipeline.model.piecewise._ppindex`): the table's (first) stress in contact, plus the continuous
    lubricant shear where the table holds two (8 columns), in either mode."""
    Q = 0.0
    if in_contact:
        Q = p.A_n * max(_ppat(friction, i, s), 0.0)
    if friction.shape[1] == 8:  # the lubricant shear, not switched
        Q += p.A_n * max(_ppat_at(friction, i, s, 4), 0.0)
    return Q


@_inline
def interface_stiffness(p, contact, adhesion, meniscus, in_contact, kk, d):
    """Add the interface tables' stiffness ``-A_n dp/dd`` [N/m] at ``d`` [m] to ``kk`` (contact in contact;
    adhesion unless it is the meniscus state, whose force does not depend on ``d`` at once)."""
    if contact is not None and in_contact:
        kk -= p.A_n * _ppval(contact, p.tab_x0, p.tab_h, d)[1]
    if adhesion is not None and meniscus is None:
        kk += p.A_n * _ppval(adhesion, p.tab_x0, p.tab_h, d)[1]
    if adhesion is not None and meniscus is not None and adhesion.shape[1] == 8:  # the part that acts at once
        kk += p.A_n * _ppslope_at(adhesion, p.tab_x0, p.tab_h, d, 4)
    return kk


@_inline
def _accelerations(p, pitch, vz, vtheta, F_f, F_r, F_i, Q):
    """``dy/dt`` (4 components) from the forces [N]; the pitch rows are zero when the pitch is locked.

    The forces are multiplied by ``1 / m`` and ``1 / I``, which depend on the parameters alone, rather than
    divided: a division's latency sat on every stage's chain (docs/kernel.md, section "Fused multiply-adds").
    """
    inv_m = 1.0 / p.m
    if pitch is None:
        return vz, 0.0, (F_f + F_r + F_i) * inv_m, 0.0
    moment = p.l_f * F_f - p.l_r * F_r - p.l_c * F_i - p.friction_arm * Q
    return vz, vtheta, (F_f + F_r + F_i) * inv_m, moment * (1.0 / p.I)


@_inline
def rhs_at(p, in_contact, z, theta, vz, vtheta, q, wc, vc, wf, vf, wr, vr, contact, adhesion, friction, tfc, pitch,
           rear_law, gap_power, meniscus):
    """``dy/dt`` at the state ``(z, theta, vz, vtheta)`` [m, rad, m/s, rad/s] (and the meniscus state ``q``
    [Pa], ignored without one) in the contact mode ``in_contact``, with the disk under the TFC point, the front
    and the rear pad at ``wc, wf, wr`` [m] moving at ``vc, vf, vr`` [m/s] (:func:`pipeline.model.piecewise.disk3`
    at the time): the equations of the module docstring, as five numbers (the last, ``dq/dt`` [Pa/s], 0
    without the meniscus state).

    The disk's position depends on the time alone, not on the state: the step looks it up at each stage's time
    beside the stage before (:func:`pipeline.model.stepper.step`), and this, inlined into the step's loop over
    its stages, is what each stage evaluates (:func:`rhs_slots` is the same arithmetic from arrays)."""
    lf = p.l_f
    F_f = -p.k_f * (z + lf * theta - wf) - p.c_f * (vz + lf * vtheta - vf)
    F_r = _rear_force(p, rear_law, z, theta, vz, vtheta, wr, vr)
    F_i = 0.0
    if gap_power is not None or tfc is not None:
        F_i = tfc_air_force(p, gap_power, tfc, gap_at(p, z, theta, wc))[0]
    F_i, Q, dq = _interface_force(p, contact, adhesion, friction, meniscus, F_i, z, theta, vz, vtheta, q, wc, vc,
                                  in_contact)
    a_z, a_theta, a_vz, a_vtheta = _accelerations(p, pitch, vz, vtheta, F_f, F_r, F_i, Q)
    return a_z, a_theta, a_vz, a_vtheta, dq


@_jit_borrowing
def rhs_slots(t, y, p, in_contact, out, dmw, contact, adhesion, friction, tfc, pitch, rear_law, gap_power,
              meniscus):
    """Write ``dy/dt`` into ``out`` at the time ``t`` [s] and state ``y`` in the contact mode ``in_contact``
    (the equations of the module docstring, :func:`rhs_at`); the slots one by one, in the order of
    :data:`pipeline.model.dynamics.SLOTS`. What the kernel's loop and the static solver call (the Python entry:
    :func:`pipeline.model.dynamics.rhs`); the step evaluates :func:`rhs_at` inlined. Compiled without
    reference counts (:data:`pipeline.model.compiled.BORROWING`): it allocates nothing."""
    z, theta, vz, vtheta = y[Z], y[THETA], y[Z_RATE], y[THETA_RATE]
    wc, vc, wf, vf, wr, vr = disk3(p, dmw, t)
    q = 0.0
    if meniscus is not None:
        q = y[MENISCUS]
    out[Z], out[THETA], out[Z_RATE], out[THETA_RATE], dq = rhs_at(
        p, in_contact, z, theta, vz, vtheta, q, wc, vc, wf, vf, wr, vr, contact, adhesion, friction, tfc, pitch,
        rear_law, gap_power, meniscus)
    if meniscus is not None:
        out[MENISCUS] = dq
