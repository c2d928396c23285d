"""Axial (tension–strain) laws, construction-time validation and derivative safety.

No static solve here: everything is elementwise and cheap, so the laws are checked
against their defining equations at many strains.
"""

from __future__ import annotations

import math
import re

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import moorjax as mj
from moorjax.element import ConsistentMass, LinearElement

# Wu et al. (2018) polyester constants used throughout
RHOL, ALPHA, BETA, BS = 10.8, 2.5, 2.0, 2.7e6
WU_SINGULAR = BS / (RHOL * BETA * 1e6)  # strain where the exact law blows up (0.125)

MBL, MA, MB = 8.0e6, 20.0, 15.0
MBL_SINGULAR = 1.0 / MB  # 0.0667


def tension(law, eps):
    return np.asarray(law.tension(jnp.asarray(eps, dtype=float)))


def dtension(law, eps):
    """dT/dε by AD at each strain."""
    return np.asarray(jax.vmap(jax.grad(lambda e: law.tension(e)))(jnp.asarray(eps, dtype=float)))


# --------------------------------------------------------------------------- laws


def test_import_enables_float64():
    assert jnp.asarray(1.0).dtype == jnp.float64


def test_linear_ea_hooke_and_tension_only():
    law = mj.LinearEA(3.5e8)
    eps = np.array([0.0, 1e-6, 1e-3, 0.02, 0.3])
    np.testing.assert_allclose(tension(law, eps), 3.5e8 * eps, rtol=1e-15, atol=0)
    # slack segments carry no compression
    np.testing.assert_array_equal(tension(law, [-1e-9, -1e-3, -0.5, -1.0]), 0.0)
    assert float(law.nominal_ea()) == 3.5e8


def test_bilateral_carries_compression_with_initial_slope():
    law = mj.Bilateral(mj.LinearEA(2.0e8))
    eps = np.array([-0.5, -0.01, -1e-6, 0.0, 1e-4, 0.05])
    np.testing.assert_allclose(tension(law, eps), 2.0e8 * eps, rtol=1e-15)

    wu = mj.PolyesterWu(RHOL, ALPHA, BETA, BS)
    bi = mj.Bilateral(wu)
    ea0 = RHOL * ALPHA * 1e6
    np.testing.assert_allclose(tension(bi, [-0.02, -0.001]), ea0 * np.array([-0.02, -0.001]), rtol=1e-14)
    # tension side is the wrapped law itself
    pos = np.array([0.001, 0.05, 0.11, 0.2])
    np.testing.assert_allclose(tension(bi, pos), tension(wu, pos), rtol=1e-15)
    # slope continuous through 0 (the compression side follows nominal EA)
    np.testing.assert_allclose(dtension(bi, [-1e-9, 1e-9]), [ea0, ea0], rtol=1e-6)


@pytest.mark.parametrize("beta", [BETA, 0.5])
def test_polyester_wu_solves_its_implicit_law_exactly(beta):
    law = mj.PolyesterWu(RHOL, ALPHA, beta, BS)
    singular = BS / (RHOL * beta * 1e6)
    eps = np.array([1e-6, 1e-3, 0.01, 0.3, 0.6, 0.85, 0.899]) * singular
    t = tension(law, eps)
    assert np.all(t > 0)
    ae = RHOL * (ALPHA + beta * t / BS) * 1e6
    # ε = T / AE(T): residual at round-off level, relative to ε
    np.testing.assert_allclose(t / ae, eps, rtol=1e-12)
    # the stiffness grows with load: secant EA = T/ε equals AE(T) > RHOL·α·1e6
    np.testing.assert_allclose(t / eps, ae, rtol=1e-12)
    assert np.all(np.diff(t / eps) > 0)
    assert float(law.nominal_ea()) == pytest.approx(RHOL * ALPHA * 1e6, rel=1e-15)
    # small-strain slope is the nominal EA
    assert dtension(law, [1e-10])[0] == pytest.approx(RHOL * ALPHA * 1e6, rel=1e-8)


def test_polyester_wu_is_capped_beyond_singular_strain():
    law = mj.PolyesterWu(RHOL, ALPHA, BETA, BS)  # cap = 0.9
    e_cap = 0.9 * WU_SINGULAR
    eps = np.array([0.5, 0.89, 0.9, 0.9 + 1e-9, 0.95, 1.0, 1.01, 1.5, 4.0, 40.0]) * WU_SINGULAR
    t = tension(law, eps)
    assert np.all(np.isfinite(t))
    assert np.all(np.diff(t) > 0), t
    # continued linearly with the slope at the cap: C¹ at the cap
    slope = dtension(law, [e_cap * (1 - 1e-9), e_cap * (1 + 1e-9), 2 * WU_SINGULAR, 10 * WU_SINGULAR])
    assert np.all(np.isfinite(slope)) and np.all(slope > 0)
    np.testing.assert_allclose(slope, slope[0], rtol=1e-6)
    t_cap = tension(law, [e_cap])[0]
    slope_cap = RHOL * 1e6 * ALPHA / (1 - 0.9) ** 2  # dT/dε of the exact law at the cap
    np.testing.assert_allclose(slope[2:], slope_cap, rtol=1e-12)
    np.testing.assert_allclose(
        tension(law, [2 * WU_SINGULAR]), t_cap + slope_cap * (2 * WU_SINGULAR - e_cap), rtol=1e-12
    )
    # below the cap the law is exact: T(cap) solves ε = T/AE(T)
    assert t_cap / (RHOL * (ALPHA + BETA * t_cap / BS) * 1e6) == pytest.approx(e_cap, rel=1e-12)


def test_polyester_wu_custom_cap():
    law = mj.PolyesterWu(RHOL, ALPHA, BETA, BS, cap=0.5)
    e = 0.7 * WU_SINGULAR  # beyond this cap, still below the default cap
    t = tension(law, [e])[0]
    exact = e * RHOL * 1e6 * ALPHA / (1 - e / WU_SINGULAR)
    assert t < exact  # linear continuation lies below the convex exact law
    assert np.isfinite(t) and t > 0


def test_polyester_mbl_solves_its_implicit_law_exactly():
    law = mj.PolyesterMBL(MBL, MA, MB)
    eps = np.array([1e-7, 1e-4, 0.005, 0.02, 0.05, 0.059])
    assert eps[-1] < 0.9 * MBL_SINGULAR
    t = tension(law, eps)
    ea = MBL * (MA + MB * t / MBL)
    np.testing.assert_allclose(t / ea, eps, rtol=1e-12)
    assert float(law.nominal_ea()) == pytest.approx(MBL * MA, rel=1e-15)
    assert dtension(law, [1e-12])[0] == pytest.approx(MBL * MA, rel=1e-8)
    # beyond the cap: finite, increasing, C¹
    far = np.array([0.059, 0.06, 0.0667, 0.07, 0.1, 1.0, 10.0])
    tf = tension(law, far)
    assert np.all(np.isfinite(tf)) and np.all(np.diff(tf) > 0)
    e_cap = 0.9 * MBL_SINGULAR
    s = dtension(law, [e_cap * (1 - 1e-9), e_cap * (1 + 1e-9), 5.0])
    np.testing.assert_allclose(s, s[0], rtol=1e-6)
    # tension-only
    np.testing.assert_array_equal(tension(law, [-0.01, -1e-12]), 0.0)


def test_polyester_wu_and_mbl_agree_when_equivalent():
    """Wu (scale S = RHOL·1e6) equals the MBL form with α' = S·α/MBL and β' = S·β/Bs."""
    # MBL form: EA = MBL·α' + β'·T ; Wu form: AE = RHOL·1e6·α + RHOL·1e6·β·T/Bs
    mbl = 5.0e6
    a_m = RHOL * 1e6 * ALPHA / mbl
    b_m = RHOL * 1e6 * BETA / BS
    wu = mj.PolyesterWu(RHOL, ALPHA, BETA, BS)
    m = mj.PolyesterMBL(mbl, a_m, b_m)
    eps = np.linspace(0.0, 0.3, 31)
    np.testing.assert_allclose(tension(m, eps), tension(wu, eps), rtol=1e-12)


def test_tabulated_ea_interpolates_and_extrapolates():
    law = mj.TabulatedEA([0.0, 0.01, 0.03], [0.0, 1.0e6, 5.0e6])
    np.testing.assert_allclose(
        tension(law, [0.0, 0.005, 0.01, 0.02, 0.03]), [0.0, 0.5e6, 1.0e6, 3.0e6, 5.0e6], rtol=1e-14
    )
    # last slope 2e8 N continued
    np.testing.assert_allclose(tension(law, [0.04, 0.13]), [7.0e6, 25.0e6], rtol=1e-12)
    np.testing.assert_array_equal(tension(law, [-0.01, -1.0]), 0.0)
    assert float(law.nominal_ea()) == pytest.approx(1.0e8)


def test_tabulated_ea_prefixes_origin():
    law = mj.TabulatedEA([0.02, 0.04], [2.0e6, 6.0e6])
    np.testing.assert_allclose(tension(law, [0.01, 0.02, 0.03, 0.05]), [1e6, 2e6, 4e6, 8e6], rtol=1e-14)
    assert float(law.nominal_ea()) == pytest.approx(1.0e8)


def test_tabulated_ea_slack_segment_carries_no_tension():
    """A table with T(0) > 0 must not make slack segments pull (tension-only contract)."""
    with pytest.raises(ValueError) as info:
        mj.TabulatedEA([0.0, 0.01, 0.02], [1.0e5, 1.0e6, 3.0e6])
    msg = str(info.value)
    assert "tension at strain 0" in msg and "100000.0 N" in msg, msg
    # a table starting at (0, 0) is fine and slack segments carry nothing
    law = mj.TabulatedEA([0.0, 0.01, 0.02], [0.0, 1.0e6, 3.0e6])
    np.testing.assert_array_equal(tension(law, [-0.05, -1e-6]), 0.0)


@pytest.mark.parametrize(
    "strain, tens",
    [
        ([0.0, 0.02, 0.01], [0.0, 1e6, 2e6]),  # decreasing
        ([0.0, 0.01, 0.01], [0.0, 1e6, 2e6]),  # repeated
    ],
)
def test_tabulated_ea_rejects_non_increasing_strains(strain, tens):
    with pytest.raises(ValueError, match="strictly increasing"):
        mj.TabulatedEA(strain, tens)


@pytest.mark.parametrize(
    "strain, tens, fragment",
    [
        ([0.0, 0.01], [0.0, 1e6, 2e6], "matching"),
        ([0.0, 0.01], [0.0, -1e6], "tabulated tension"),
        ([-0.01, 0.01], [0.0, 1e6], "tabulated strain"),
        ([0.0, np.nan], [0.0, 1e6], "not finite"),
        ([0.0], [0.0], "at least one point"),
    ],
)
def test_tabulated_ea_rejects_bad_tables(strain, tens, fragment):
    with pytest.raises(ValueError, match=fragment):
        mj.TabulatedEA(strain, tens)


# ------------------------------------------------------------------ validation


def _assert_names(excinfo, name, unit):
    msg = str(excinfo.value)
    assert name in msg, msg
    # the unit follows the value: "<name> = <value> <unit> ..."
    assert re.search(re.escape(name) + r" = \S+ " + re.escape(unit) + r"( |$)", msg), msg


BAD = [-1.0, 0.0, math.nan, math.inf, -math.inf]


@pytest.mark.parametrize("bad", BAD)
@pytest.mark.parametrize(
    "make, name, unit",
    [
        (lambda v: mj.LinearEA(v), "EA", "N"),
        (lambda v: mj.LineType(diameter=v, mass_per_length=77.7, axial=3.8e8), "diameter", "m"),
        (lambda v: mj.LineType(0.09, v, 3.8e8), "mass per length", "kg/m"),
        (lambda v: mj.LineType(0.09, 77.7, v), "EA", "N"),
        (lambda v: mj.LineType(0.09, 77.7, 3.8e8, mbl=v), "MBL", "N"),
        (lambda v: mj.PolyesterWu(v, ALPHA, BETA, BS), "RHOL", "kg/m"),
        (lambda v: mj.PolyesterWu(RHOL, v, BETA, BS), "alpha", "-"),
        (lambda v: mj.PolyesterWu(RHOL, ALPHA, BETA, v), "breaking strength Bs", "N"),
        (lambda v: mj.PolyesterMBL(v, MA, MB), "MBL", "N"),
        (lambda v: mj.PolyesterMBL(MBL, v, MB), "alpha", "-"),
        (lambda v: mj.Environment(depth=v), "water depth", "m"),
        (lambda v: mj.Seabed(stiffness=v), "seabed stiffness kBot", "Pa/m"),
        (lambda v: mj.SinePath([0, 0, -5], [1, 0, 0], v), "path period", "s"),
        (
            lambda v: mj.Line(mj.LineType(0.09, 77.7, 3.8e8), v, 10, mj.FixedEnd([-100, 0, -50]), mj.FixedEnd([0, 0, -5])),
            "line length",
            "m",
        ),
    ],
)
def test_constructors_reject_nonpositive_or_nonfinite(make, name, unit, bad):
    with pytest.raises(ValueError) as info:
        make(bad)
    _assert_names(info, name, unit)
    if not math.isfinite(bad):
        assert "not finite" in str(info.value)


@pytest.mark.parametrize("bad", [-1.0, math.nan, math.inf])
@pytest.mark.parametrize(
    "make, name, unit",
    [
        (lambda v: mj.PolyesterWu(RHOL, ALPHA, v, BS), "beta", "-"),
        (lambda v: mj.PolyesterMBL(MBL, MA, v), "beta", "-"),
        (lambda v: mj.LineType(0.09, 77.7, 3.8e8, damping=v), "internal damping BA", "N·s"),
        # 0 is allowed, as in MoorDyn: rho = 0 is air, g = 0 weightless
        (lambda v: mj.Environment(320.0, rho=v), "water density", "kg/m³"),
        (lambda v: mj.Environment(320.0, g=v), "gravity", "m/s²"),
        (lambda v: mj.MorisonDrag(v), "Cd normal", "-"),
        (lambda v: mj.AddedMass(1.0, v), "Ca axial", "-"),
        (lambda v: mj.Seabed(damping=v), "seabed damping cBot", "Pa·s/m"),
        (lambda v: mj.SeabedFriction(v), "seabed friction coefficient", "-"),
    ],
)
def test_constructors_reject_negative_or_nonfinite(make, name, unit, bad):
    with pytest.raises(ValueError) as info:
        make(bad)
    _assert_names(info, name, unit)


def test_zero_allowed_where_documented_nonnegative():
    mj.PolyesterWu(RHOL, ALPHA, 0.0, BS)
    mj.LineType(0.09, 77.7, 3.8e8, damping=0.0)
    mj.MorisonDrag(0.0, 0.0)
    mj.Seabed(damping=0.0)


@pytest.mark.parametrize("point", [[0.0, math.nan, -5.0], [math.inf, 0.0, 0.0]])
def test_fixed_end_rejects_nonfinite(point):
    with pytest.raises(ValueError) as info:
        mj.FixedEnd(point)
    assert "end position" in str(info.value) and " m " in str(info.value)


def test_number_becomes_linear_ea():
    lt = mj.LineType(0.09, 77.7066, 384.243e6)
    assert isinstance(lt.axial, mj.LinearEA)
    assert float(lt.axial.ea) == 384.243e6
    # wet weight (m − ρ·πd²/4)·g, negative for a buoyant section
    assert float(lt.wet_weight(1025.0, 9.80665)) == pytest.approx(
        (77.7066 - 1025.0 * math.pi * 0.09**2 / 4) * 9.80665, rel=1e-14
    )
    assert float(mj.LineType(0.12, 10.8, 1.5e8).wet_weight(1025.0, 9.80665)) < 0


# ----------------------------------------------------------- parameter gradients

LAWS = {
    "linear": mj.LinearEA(3.8e8),
    "bilateral": mj.Bilateral(mj.LinearEA(3.8e8)),
    "wu": mj.PolyesterWu(RHOL, ALPHA, BETA, BS),
    "mbl": mj.PolyesterMBL(MBL, MA, MB),
    "table": mj.TabulatedEA([0.0, 0.01, 0.03], [0.0, 1.0e6, 5.0e6]),
}


@pytest.mark.parametrize("name", sorted(LAWS))
@pytest.mark.parametrize("eps", [0.0, -0.02, -1.0, 1e-3, 0.5])
def test_parameter_gradients_finite(name, eps):
    law = LAWS[name]
    g = eqx.filter_grad(lambda lw: lw.tension(jnp.asarray(eps)))(law)
    leaves = jax.tree_util.tree_leaves(g)
    assert leaves
    for leaf in leaves:
        assert np.all(np.isfinite(np.asarray(leaf))), (name, eps, g)
    # strain derivative finite too
    assert np.isfinite(float(jax.grad(lambda e: law.tension(e))(jnp.asarray(eps))))
    if eps < 0 and name not in ("bilateral", "table"):
        # slack: no tension, no sensitivity
        for leaf in leaves:
            np.testing.assert_array_equal(np.asarray(leaf), 0.0)


@pytest.mark.parametrize("eps", [0.0, -0.02, 1e-3, 0.05, 0.5])
@pytest.mark.parametrize("kind", ["wu", "mbl"])
def test_zero_beta_parameter_gradients_finite_and_exact(kind, eps):
    """β = 0 is accepted (constant stiffness); gradients there must be finite and exact.

    With S the stiffness scale (RHOL·1e6 or MBL) and B the normalising load (Bs or
    MBL), T = ε·S·α/(1 − ε·S·β/B), so at β = 0: dT/dα = ε·S, dT/dβ = ε²·S²·α/B.
    """
    if kind == "wu":
        law, s_scale, b_norm = mj.PolyesterWu(RHOL, ALPHA, 0.0, BS), RHOL * 1e6, BS
    else:
        law, s_scale, b_norm = mj.PolyesterMBL(MBL, MA, 0.0), MBL, MBL
    alpha = float(law.alpha)
    e = max(eps, 0.0)
    assert float(law.tension(jnp.asarray(eps))) == pytest.approx(e * s_scale * alpha, rel=1e-14)
    g = eqx.filter_grad(lambda lw: lw.tension(jnp.asarray(eps)))(law)
    for leaf in jax.tree_util.tree_leaves(g):
        assert np.all(np.isfinite(np.asarray(leaf))), g
    assert float(g.alpha) == pytest.approx(e * s_scale, rel=1e-12, abs=1e-12)
    assert float(g.beta) == pytest.approx(e**2 * s_scale**2 * alpha / b_norm, rel=1e-9, abs=1e-12)


def test_parameter_gradients_match_finite_differences():
    eps = 0.05
    law = mj.PolyesterWu(RHOL, ALPHA, BETA, BS)
    g = eqx.filter_grad(lambda lw: lw.tension(jnp.asarray(eps)))(law)
    for field in ("rhol", "alpha", "beta", "breaking_strength"):
        p = float(getattr(law, field))
        h = 1e-6 * p

        def at(v):
            return float(eqx.tree_at(lambda lw: getattr(lw, field), law, jnp.asarray(v)).tension(jnp.asarray(eps)))

        fd = (at(p + h) - at(p - h)) / (2 * h)
        assert float(getattr(g, field)) == pytest.approx(fd, rel=1e-6), field
    # LinearEA: dT/dEA = ε
    gl = eqx.filter_grad(lambda lw: lw.tension(jnp.asarray(eps)))(mj.LinearEA(3e8))
    assert float(gl.ea) == pytest.approx(eps, rel=1e-15)


def test_laws_are_jittable_without_recompiling_on_value_change():
    traces = []

    @eqx.filter_jit
    def f(law, e):
        traces.append(1)
        return law.tension(e)

    f(mj.PolyesterWu(RHOL, ALPHA, BETA, BS), jnp.asarray(0.01))
    f(mj.PolyesterWu(2 * RHOL, 3.0, 1.0, 2 * BS), jnp.asarray(0.02))
    assert len(traces) == 1


# ----------------------------------------------------------- derivative safety


def _line(n=4, drag=True, added=True, damping=1.0e5, axial=3.8e8):
    lt = mj.LineType(
        0.09,
        77.7066,
        axial,
        damping=damping,
        drag=mj.MorisonDrag(1.6, 0.1) if drag else None,
        added_mass=mj.AddedMass(1.0, 0.5) if added else None,
    )
    return mj.Line(lt, 100.0, n, mj.FixedEnd([-90.0, 0.0, -60.0]), mj.FixedEnd([0.0, 0.0, -10.0]))


def _nodes(line):
    st = line.straight_state()
    r, v = line.nodes(0.0, st)
    # put some sag in so segments are not collinear
    r = r.at[1:-1, 2].add(-jnp.array([3.0, 4.0, 3.0]))
    return r, v


ENVS = {
    "still": mj.Environment(100.0),
    "seabed_friction": mj.Environment(50.0, seabed=mj.Seabed(friction=mj.SeabedFriction(0.5))),
    "uniform_current": mj.Environment(100.0, current=mj.UniformCurrent([0.8, 0.3, 0.0])),
    "profile_current": mj.Environment(
        100.0, current=mj.ProfileCurrent([-100.0, 0.0], [[0.2, 0.0, 0.0], [1.0, 0.5, 0.0]])
    ),
}


@pytest.mark.parametrize("env_name", sorted(ENVS))
def test_jacobian_wrt_velocity_at_rest_is_finite(env_name):
    env = ENVS[env_name]
    line = _line()
    r, _ = _nodes(line)
    if env.current is None:
        v = jnp.zeros_like(r)
    else:  # at rest relative to the water: relative velocity zero
        v = env.current.velocity(r[:, 2])
    el = LinearElement()
    jac = jax.jacfwd(lambda vv: el.nodal_forces(line, env, r, vv))(v)
    assert jac.shape == (5, 3, 5, 3)
    assert np.all(np.isfinite(np.asarray(jac))), env_name
    # quadratic drag has no linearisation at zero relative velocity, so the velocity
    # Jacobian is that of the internal damping alone (no drag)
    nodrag = eqx.tree_at(lambda ln: ln.line_type.drag, line, None)
    still = mj.Environment(float(env.depth))
    jac0 = np.asarray(jax.jacfwd(lambda vv: el.nodal_forces(nodrag, still, r, vv))(v))
    assert np.abs(jac0).max() > 0  # damping BA couples velocities
    expected = jac0.copy()
    if env.seabed is not None:
        # regularised Coulomb friction is viscous at rest: dF_h/du_h = −μ·N/v_slip
        # on every node in contact (N = kBot·δ·d·l_node); nodes 0 and 1 touch here
        bed, d, l = env.seabed, 0.09, 25.0
        pen = np.asarray(-env.depth - r[:, 2])
        assert pen[0] > 0 and pen[1] > 0 and np.all(pen[2:] < 0)
        node_len = np.array([l / 2, l, l, l, l / 2])
        normal = np.where(pen > 0, float(bed.stiffness) * pen * d * node_len, 0.0)
        c = float(bed.friction.mu) * normal / float(bed.friction.v_slip)
        for k in range(5):
            for i in range(2):
                expected[k, i, k, i] -= c[k]
            # seabed damping −cBot·ż·d·l_node on the vertical
            expected[k, 2, k, 2] -= float(bed.damping) * d * node_len[k] * (pen[k] > 0)
    np.testing.assert_allclose(np.asarray(jac), expected, rtol=1e-12, atol=1e-6)


def test_jacobian_wrt_velocity_at_rest_no_damping_is_zero():
    env = mj.Environment(100.0)
    line = _line(damping=0.0)
    r, v = _nodes(line)
    jac = jax.jacfwd(lambda vv: LinearElement().nodal_forces(line, env, r, vv))(v)
    np.testing.assert_array_equal(np.asarray(jac), 0.0)


@pytest.mark.parametrize("axial", ["linear", "bilateral"])
@pytest.mark.parametrize("env_name", ["still", "seabed_friction", "uniform_current"])
def test_jacobian_wrt_positions_with_zero_length_segment_is_finite(axial, env_name):
    env = ENVS[env_name]
    law = mj.LinearEA(3.8e8) if axial == "linear" else mj.Bilateral(mj.LinearEA(3.8e8))
    line = _line(axial=law)
    r, v = _nodes(line)
    r = r.at[2].set(r[1])  # two coincident nodes: segment 1 has zero length
    v = v.at[1:-1].set(0.1)  # moving nodes (drag, damping active)
    el = LinearElement()
    f = el.nodal_forces(line, env, r, v)
    assert np.all(np.isfinite(np.asarray(f)))
    jr = jax.jacfwd(lambda rr: el.nodal_forces(line, env, rr, v))(r)
    jv = jax.jacfwd(lambda vv: el.nodal_forces(line, env, r, vv))(v)
    assert np.all(np.isfinite(np.asarray(jr)))
    assert np.all(np.isfinite(np.asarray(jv)))
    # the zero-length segment has no direction: it exerts no force on its nodes
    tens = el.segment_tensions(line, r, v)
    assert np.all(np.isfinite(np.asarray(tens)))
    # also accelerations (mass matrices with the undefined tangent)
    for mass in (None, ConsistentMass()):
        el2 = el if mass is None else LinearElement(mass=mass)
        ja = jax.jacfwd(lambda rr: el2.accelerations(line, env, 0.0, rr, v))(r)
        assert np.all(np.isfinite(np.asarray(ja)))


def test_jacobian_wrt_positions_matches_finite_differences():
    env = mj.Environment(100.0)
    line = _line(drag=False, added=False)
    r, v = _nodes(line)
    el = LinearElement()
    jr = np.asarray(jax.jacfwd(lambda rr: el.nodal_forces(line, env, rr, v))(r)).reshape(15, 15)
    h = 1e-6
    fd = np.zeros((15, 15))
    rf = np.asarray(r).ravel()
    for k in range(15):
        e = np.zeros(15)
        e[k] = h
        fp = el.nodal_forces(line, env, jnp.asarray((rf + e).reshape(5, 3)), v)
        fm = el.nodal_forces(line, env, jnp.asarray((rf - e).reshape(5, 3)), v)
        fd[:, k] = (np.asarray(fp) - np.asarray(fm)).ravel() / (2 * h)
    np.testing.assert_allclose(jr, fd, rtol=1e-5, atol=1e-5 * np.abs(jr).max())


def test_nodal_forces_physics_at_rest_straight_line():
    """Straight taut line: elastic forces EA·ε along the chord, weight lumped l/2, l, …, l/2."""
    env = mj.Environment(100.0)
    line = _line(drag=False, added=False, damping=0.0)
    r, v = line.nodes(0.0, line.straight_state())
    chord = float(jnp.linalg.norm(r[-1] - r[0]))
    eps = chord / 100.0 - 1.0
    assert eps > 0
    f = np.asarray(LinearElement().nodal_forces(line, env, r, v))
    w = float(line.line_type.wet_weight(env.rho, env.g))
    l = 25.0
    t_hat = np.asarray((r[-1] - r[0]) / chord)
    # interior nodes: the elastic forces cancel, only weight remains
    np.testing.assert_allclose(f[1:-1, :2], 0.0, atol=1e-6)
    np.testing.assert_allclose(f[1:-1, 2], -w * l, rtol=1e-10)
    # end A is pulled towards B with EA·ε, minus half a segment of weight
    np.testing.assert_allclose(f[0], 3.8e8 * eps * t_hat - np.array([0, 0, w * l / 2]), rtol=1e-9)
    np.testing.assert_allclose(f[-1], -3.8e8 * eps * t_hat - np.array([0, 0, w * l / 2]), rtol=1e-9)
    # total external force = total wet weight
    np.testing.assert_allclose(f.sum(axis=0), [0, 0, -w * 100.0], rtol=1e-10, atol=1e-6)
