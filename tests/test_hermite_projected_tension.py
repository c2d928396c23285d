"""The Hermite element's projected tension field (``ProjectedTension``, the default).

λ = Π T(Π ε) with ε = |r'| − 1 and Π the L2 projection within each element onto
quadratics: Wu's quadratic tension field element by element, the axial law
applied to the projected strain. Checked: the projection itself, that the
forces are the gradient of the strain energy ∫ ψ(Π ε) ds (so the stiffness is
symmetric), that a straight element is left as the strain closure has it and
that no zero-energy mode is left there (degree 1 would leave one), and case A
at 10 elements against MoorDyn's reference.
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
from moorjax.element.hermite_motion import ProjectedTension, StrainTension, projection_matrix
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


def test_a_degree_outside_the_quadrature_is_refused():
    with pytest.raises(ValueError, match="degree"):
        ProjectedTension(degree=5)
    with pytest.raises(ValueError, match="degree"):
        ProjectedTension(degree=-1)


def test_the_default_closure_is_the_projected_field_and_keeps_the_band():
    el = HermiteElement()
    assert isinstance(el.tension, ProjectedTension) and el.tension.degree == 2
    line = hermite_case_a(4).lines[0]
    assert provides_stage_factor(line)


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


def _energy(line, dofs, degree):
    """∫ ψ(Π ε) ds with ψ the tension-only linear law's energy ½·EA·max(ε, 0)²."""
    ea = float(line.line_type.axial.nominal_ea())
    _, d1, _, _ = element_fields(line, dofs)
    strain = jnp.sqrt(jnp.sum(d1 * d1, axis=-1)) - 1.0
    proj = jnp.asarray(projection_matrix(degree))
    sb = jnp.einsum("pq,nq->np", proj, strain)
    w = element_lengths(line)[:, None] * WQ
    return jnp.sum(w * 0.5 * ea * jnp.maximum(sb, 0.0) ** 2)


@pytest.mark.parametrize("seed", range(6))
def test_the_forces_are_the_gradient_of_the_projected_strain_energy(seed):
    """Generalised forces = −∂/∂(r, r') of ∫ ψ(Π ε) ds on drawn stretched and bent
    (partly slack) states of case A's chain at 5 elements; the strain closure's
    forces are not (their energy is ∫ ψ(ε) ds)."""
    line = eqx.tree_at(lambda ln: ln.line_type.damping, hermite_case_a(5).lines[0], 0.0)
    dofs = _drawn_dofs(line, seed)
    forces = _internal_forces(line, dofs)
    grad = jax.grad(lambda r, dr: _energy(line, HermiteDofs(r=r, dr=dr, lam=dofs.lam), 2),
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


def test_a_straight_element_is_left_as_the_strain_closure_has_it():
    """On a straight element ε is quadratic in ξ: the projection changes nothing
    and the forces equal the strain closure's (linear law, taut)."""
    line = eqx.tree_at(lambda ln: ln.line_type.damping, hermite_case_a(4).lines[0], 0.0)
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


def test_a_straight_taut_line_has_no_zero_energy_mode():
    """The free unknowns of a straight taut line have a definite stiffness with the
    quadratic field (every axial mode is stretched, the transverse ones held by
    the tension); a linear field leaves one mode free: the slopes' lengths
    scaled together along the whole line."""
    line = eqx.tree_at(lambda ln: ln.line_type.damping, hermite_case_a(4).lines[0], 0.0)
    dofs = _straight(line, 1)
    k2 = _free_stiffness(line, dofs)
    np.testing.assert_allclose(k2, k2.T, atol=1e-9 * np.abs(k2).max())
    ev2 = np.linalg.eigvalsh(0.5 * (k2 + k2.T))
    line1 = eqx.tree_at(lambda ln: ln.element, line, HermiteElement(tension=ProjectedTension(degree=1)))
    ev1 = np.linalg.eigvalsh(_free_stiffness(line1, dofs))
    assert ev2.max() < 0.0  # restoring in every direction
    # the weakest modes are transverse, held by the tension: ~ strain·EA/h (2.6e-4 here)
    assert np.abs(ev2).min() > 1e-5 * np.abs(ev2).max(), ev2
    assert np.sort(np.abs(ev1))[0] < 1e-9 * np.abs(ev1).max(), np.sort(np.abs(ev1))[:3]


@pytest.mark.slow
def test_case_a_at_ten_elements_is_closer_to_moordyn_than_with_the_strain_closure():
    """Case A at 10 elements over 20 s against MoorDyn's N = 160 reference (RMS of
    the fairlead |F| over the std): the projected field 1.39 %, the strain
    closure 1.82 % (benchmarks/README.md, session 44, has drawn motions too)."""
    ref = np.loadtxt(DATA / "ref_A.csv", delimiter=",", skiprows=1)
    std = np.std(np.linalg.norm(ref[:, 3:6], axis=1))
    errors = {}
    for name, tension in (("projected", ProjectedTension()), ("strain", StrainTension())):
        scene = hermite_case_a(10, element=HermiteElement(tension=tension))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = simulate(scene, 20.0)
        assert bool(res.succeeded())
        k = len(res.ts) - 1
        np.testing.assert_allclose(np.asarray(res.ts[1:]), ref[:k, 0], atol=1e-9)
        ours = np.linalg.norm(np.asarray(res.force_b[1:, 0]), axis=-1)
        errors[name] = np.sqrt(np.mean((ours - np.linalg.norm(ref[:k, 3:6], axis=1)) ** 2)) / std
    print(f"\ncase A, 10 Hermite elements, 20 s: projected {100 * errors['projected']:.3f} %, "
          f"strain {100 * errors['strain']:.3f} % of the std")
    assert errors["projected"] < 0.015, errors
    assert errors["projected"] < 0.85 * errors["strain"], errors
