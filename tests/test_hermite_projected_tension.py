"""The Hermite element's projected tension field (``ProjectedTension``, the default).

λ = Π T(Π ε) with ε = |r'| − 1 and Π the L2 projection onto Wu's continuous
quadratic field (the default) or within each element onto polynomials
(``continuous=False``): the axial law applied to the projected strain. Checked:
the projections themselves, that the forces are the gradient of the strain
energy ∫ ψ(Π ε) ds (so the stiffness is symmetric), that a straight line is
left as the strain closure has it and that no zero-energy mode is left there
(a per-element degree 1 would leave one), and cases A and B at 10 elements
against MoorDyn's references.
"""

from __future__ import annotations

import warnings

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import moorjax as mj
from moorjax.dynamics import simulate
from moorjax.element import HermiteElement
from moorjax.element.hermite import (WQ, XI, HermiteDofs, element_fields, element_lengths,
                                     generalized_forces)
from moorjax.element.hermite_motion import (ProjectedTension, StrainTension, field_gram,
                                            field_projection, projection_matrix)
from moorjax.element.hermite_stage import provides_stage_factor
from scenes import DATA, hermite_case_a


@pytest.mark.parametrize("degree", [0, 1, 2, 3])
def test_the_projection_keeps_polynomials_and_is_self_adjoint(degree):
    """Π reproduces polynomials of its degree, drops the Legendre polynomial one
    degree higher, is idempotent, and W·Π is symmetric (what makes the forces
    conservative)."""
    p = projection_matrix(degree)
    for k in range(degree + 1):
        np.testing.assert_allclose(p @ XI**k, XI**k, atol=1e-12)
    higher = np.polynomial.legendre.legval(2 * XI - 1, np.eye(degree + 2)[degree + 1])
    np.testing.assert_allclose(p @ higher, 0.0, atol=1e-12)
    np.testing.assert_allclose(p @ p, p, atol=1e-12)
    wp = np.diag(WQ) @ p
    np.testing.assert_allclose(wp, wp.T, atol=1e-14)


def test_the_continuous_projection_keeps_wu_s_field_and_is_self_adjoint():
    """Π onto Wu's continuous quadratic field (values at nodes and midpoints) on a
    graded mesh: a field of that space is kept, Π is idempotent, and
    ∫ (Π f)·g ds = ∫ f·(Π g) ds for drawn f, g."""
    element = HermiteElement(mesh=np.array([1.0, 2.5, 0.7, 1.6, 1.2]))
    line = hermite_case_a(5, element=element).lines[0]
    gram = field_gram(line)
    rng = np.random.default_rng(3)
    values = rng.normal(size=2 * 5 + 1)
    idx = 2 * np.arange(5)[:, None] + np.arange(3)[None, :]
    from moorjax.element.hermite import P

    field = np.einsum("mq,nm->nq", P, values[idx])
    np.testing.assert_allclose(np.asarray(field_projection(line, gram, jnp.asarray(field))), field,
                               atol=1e-12 * np.abs(field).max())
    f, g = (jnp.asarray(rng.normal(size=(5, len(XI)))) for _ in range(2))
    pf, pg = field_projection(line, gram, f), field_projection(line, gram, g)
    np.testing.assert_allclose(np.asarray(field_projection(line, gram, pf)), np.asarray(pf), atol=1e-12)
    w = element_lengths(line)[:, None] * WQ
    np.testing.assert_allclose(float(jnp.sum(w * pf * g)), float(jnp.sum(w * f * pg)), rtol=1e-12)


def test_a_degree_outside_the_quadrature_is_refused():
    with pytest.raises(ValueError, match="degree"):
        ProjectedTension(degree=5, continuous=False)
    with pytest.raises(ValueError, match="degree"):
        ProjectedTension(degree=-1, continuous=False)
    with pytest.raises(ValueError, match="continuous"):
        ProjectedTension(degree=1)  # Wu's continuous field is quadratic
    assert ProjectedTension(degree=1, continuous=False).degree == 1


def test_the_default_closure_is_wu_s_continuous_field_and_keeps_the_band():
    el = HermiteElement()
    assert isinstance(el.tension, ProjectedTension)
    assert el.tension.degree == 2 and el.tension.continuous
    assert el.tension.stage_closure() == ProjectedTension(continuous=False)
    line = hermite_case_a(4).lines[0]
    assert provides_stage_factor(line)


CLOSURES = {"continuous": ProjectedTension(), "per-element": ProjectedTension(continuous=False)}


def _with(line, closure):
    return eqx.tree_at(lambda ln: ln.element, line, HermiteElement(tension=closure))


def _project(line, closure, f):
    if closure.continuous:
        return field_projection(line, field_gram(line), f)
    return jnp.einsum("pq,nq->np", jnp.asarray(projection_matrix(closure.degree)), f)


def _drawn_dofs(line, seed, scale=0.05):
    """Case A's straight chord from anchor to fairlead, stretched and bent by drawn
    offsets of the nodes [m] and slopes [-]."""
    n = line.n_segments
    ra, rb = np.asarray(line.end_a.position(0.0)), np.asarray(line.end_b.position(0.0))
    s = np.linspace(0.0, 1.0, n + 1)[:, None]
    chord = rb - ra
    rng = np.random.default_rng(seed)
    r = ra + s * chord + rng.normal(size=(n + 1, 3)) * scale * float(line.segment_length)
    r[0], r[-1] = ra, rb
    dr = chord / line.length + rng.normal(size=(n + 1, 3)) * scale
    return HermiteDofs(r=jnp.asarray(r), dr=jnp.asarray(dr), lam=jnp.zeros(2 * n + 1))


def _internal_forces(line, dofs):
    """The generalised forces of the tension alone (loads subtracted), flattened."""
    env = mj.Environment(320.0)
    full, tension = line.element.tension.resolve(line, dofs)
    f, m = generalized_forces(line, env, full, None, 0.0, tension)
    f0, m0 = generalized_forces(line, env, full, None, 0.0, (jnp.zeros_like(tension[0]), tension[1]))
    return jnp.concatenate([(f - f0).ravel(), (m - m0).ravel()])


def _energy(line, dofs, closure):
    """∫ ψ(Π ε) ds with ψ the tension-only linear law's energy ½·EA·max(ε, 0)²."""
    ea = float(line.line_type.axial.nominal_ea())
    _, d1, _, _ = element_fields(line, dofs)
    strain = jnp.sqrt(jnp.sum(d1 * d1, axis=-1)) - 1.0
    sb = _project(line, closure, strain)
    w = element_lengths(line)[:, None] * WQ
    return jnp.sum(w * 0.5 * ea * jnp.maximum(sb, 0.0) ** 2)


@pytest.mark.parametrize("name", sorted(CLOSURES))
@pytest.mark.parametrize("seed", range(4))
def test_the_forces_are_the_gradient_of_the_projected_strain_energy(seed, name):
    """Generalised forces = −∂/∂(r, r') of ∫ ψ(Π ε) ds on drawn stretched and bent
    (partly slack) states of case A's chain at 5 elements; the strain closure's
    forces are not (their energy is ∫ ψ(ε) ds)."""
    closure = CLOSURES[name]
    line = _with(eqx.tree_at(lambda ln: ln.line_type.damping, hermite_case_a(5).lines[0], 0.0), closure)
    dofs = _drawn_dofs(line, seed)
    forces = _internal_forces(line, dofs)
    grad = jax.grad(lambda r, dr: _energy(line, HermiteDofs(r=r, dr=dr, lam=dofs.lam), closure),
                    argnums=(0, 1))(dofs.r, dofs.dr)
    expected = -jnp.concatenate([grad[0].ravel(), grad[1].ravel()])
    scale = float(jnp.max(jnp.abs(expected)))
    assert scale > 1e5  # the drawn state is stretched
    np.testing.assert_allclose(np.asarray(forces), np.asarray(expected), atol=1e-9 * scale)
    strain_line = eqx.tree_at(lambda ln: ln.element, line, HermiteElement(tension=StrainTension()))
    assert float(jnp.max(jnp.abs(_internal_forces(strain_line, dofs) - expected))) > 1e-3 * scale


def _straight(line, seed):
    """Case A's chord straight and taut, its slopes along it with a drawn quadratic
    stretch per node (so ε is the cubic's own, quadratic in each element)."""
    n = line.n_segments
    ra, rb = np.asarray(line.end_a.position(0.0)), np.asarray(line.end_b.position(0.0))
    e = (rb - ra) / np.linalg.norm(rb - ra)
    rng = np.random.default_rng(seed)
    stretch = 1.0 + rng.uniform(1e-3, 4e-3, n + 1)
    h = float(line.segment_length)
    r = [ra]
    for k in range(n):  # ∫ of the cubic's r' along e over element k: h·(s_k + s_{k+1})/2 + O(h·Δs)
        r.append(r[-1] + e * h * 0.5 * (stretch[k] + stretch[k + 1]))
    return HermiteDofs(r=jnp.asarray(np.array(r)), dr=jnp.asarray(stretch[:, None] * e),
                       lam=jnp.zeros(2 * n + 1))


@pytest.mark.parametrize("name", sorted(CLOSURES))
def test_a_straight_line_is_left_as_the_strain_closure_has_it(name):
    """On a straight line ε is a continuous piecewise quadratic: either projection
    changes nothing and the forces equal the strain closure's (linear law, taut)."""
    line = _with(eqx.tree_at(lambda ln: ln.line_type.damping, hermite_case_a(4).lines[0], 0.0),
                 CLOSURES[name])
    dofs = _straight(line, 0)
    projected = _internal_forces(line, dofs)
    strain_line = eqx.tree_at(lambda ln: ln.element, line, HermiteElement(tension=StrainTension()))
    scale = float(jnp.max(jnp.abs(projected)))
    np.testing.assert_allclose(np.asarray(projected), np.asarray(_internal_forces(strain_line, dofs)),
                               atol=1e-10 * scale)


def _free_stiffness(line, dofs):
    """The tension's stiffness over the free unknowns (interior positions, all
    slopes), scaled to EA/h per unit of position and slope·h."""
    n, h = line.n_segments, line.segment_length
    ea = float(line.line_type.axial.nominal_ea())

    def f(y):
        r = dofs.r.at[1:-1].set(y[: 3 * (n - 1)].reshape(n - 1, 3))
        dr = y[3 * (n - 1):].reshape(n + 1, 3) / h
        full = _internal_forces(line, HermiteDofs(r=r, dr=dr, lam=dofs.lam))
        fr, mr = full[: 3 * (n + 1)].reshape(n + 1, 3), full[3 * (n + 1):].reshape(n + 1, 3)
        return jnp.concatenate([fr[1:-1].ravel(), (mr / h).ravel()]) / ea * h

    y0 = jnp.concatenate([dofs.r[1:-1].ravel(), (dofs.dr * h).ravel()])
    return np.asarray(jax.jacfwd(f)(y0))


@pytest.mark.parametrize("name", sorted(CLOSURES))
def test_a_straight_taut_line_has_no_zero_energy_mode(name):
    """The free unknowns of a straight taut line have a definite stiffness with the
    quadratic fields (every axial mode is stretched, the transverse ones held by
    the tension); a per-element linear field leaves one mode free: the slopes'
    lengths scaled together along the whole line."""
    line = _with(eqx.tree_at(lambda ln: ln.line_type.damping, hermite_case_a(4).lines[0], 0.0),
                 CLOSURES[name])
    dofs = _straight(line, 1)
    k2 = _free_stiffness(line, dofs)
    np.testing.assert_allclose(k2, k2.T, atol=1e-9 * np.abs(k2).max())
    ev2 = np.linalg.eigvalsh(0.5 * (k2 + k2.T))
    line1 = _with(line, ProjectedTension(degree=1, continuous=False))
    ev1 = np.linalg.eigvalsh(_free_stiffness(line1, dofs))
    assert ev2.max() < 0.0  # restoring in every direction
    # the weakest modes are transverse, held by the tension: ~ strain·EA/h (2.6e-4 here)
    assert np.abs(ev2).min() > 1e-5 * np.abs(ev2).max(), ev2
    assert np.sort(np.abs(ev1))[0] < 1e-9 * np.abs(ev1).max(), np.sort(np.abs(ev1))[:3]


@pytest.mark.slow
def test_cases_a_and_b_at_ten_elements_are_within_one_percent_of_moordyn():
    """Issue 13: cases A and B at 10 Hermite elements over 60 s against MoorDyn's
    N = 160 references (RMS of the fairlead |F| over the std), the default
    closure: measured A 0.92 %, B 0.72 % (the strain closure: A 1.53 %;
    benchmarks/README.md, session 44, has drawn motions too)."""
    from scenes import case_b_scene

    def error(case, scene):
        ref = np.loadtxt(DATA / f"ref_{case}.csv", delimiter=",", skiprows=1)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = simulate(scene, 60.0)
        assert bool(res.succeeded())
        k = len(res.ts) - 1
        np.testing.assert_allclose(np.asarray(res.ts[1:]), ref[:k, 0], atol=1e-9)
        ours = np.linalg.norm(np.asarray(res.force_b[1:, 0]), axis=-1)
        force = np.linalg.norm(ref[:k, 3:6], axis=1)
        return np.sqrt(np.mean((ours - force) ** 2)) / np.std(np.linalg.norm(ref[:, 3:6], axis=1))

    b = case_b_scene(10)
    b = mj.Scene([mj.Line(ln.line_type, ln.length, ln.n_segments, ln.end_a, ln.end_b,
                          element=HermiteElement()) for ln in b.lines], b.env)
    errors = {"A": error("A", hermite_case_a(10)), "B": error("B", b),
              "A, strain closure": error("A", hermite_case_a(10, element=HermiteElement(
                  tension=StrainTension())))}
    print("\n10 Hermite elements, 60 s: " + ", ".join(f"{k} {100 * v:.3f} %" for k, v in errors.items()))
    assert errors["A"] < 0.01 and errors["B"] < 0.01, errors
    assert errors["A"] < 0.7 * errors["A, strain closure"], errors
