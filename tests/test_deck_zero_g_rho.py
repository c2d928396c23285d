"""``g = 0`` and water density 0 in decks, accepted where MoorDyn accepts them.

MoorDyn v2 reads ``g`` and ``rho`` (``WtrDnsty``) as plain numbers (its
public test decks run weightless, ``g = 0``, and in air, ``rho = 0``); so does
moorjax now, with the physics that follows: no weight (g = 0), no buoyancy,
drag or added mass (rho = 0).

- a taut weightless line: the chord is in equilibrium with tension
  EA·(chord/L − 1) at both ends, exactly;
- a hanging line in air (rho = 0): MoorPy's catenary with the dry weight m·g;
- negative values are still refused, naming the option and its unit.
"""

from __future__ import annotations

import numpy as np
import pytest

from moorjax.io import build_scene, parse_deck
from moorjax.io.errors import InputError
from moorjax.statics import solve_line_statics

DECK = """title
---------------------- LINE TYPES -----------------------------------
TypeName   Diam    Mass/m     EA     BA/-zeta    EI   Cd   Ca   CdAx  CaAx
(name)     (m)     (kg/m)     (N)    (N-s/-)     (-)  (-)  (-)  (-)   (-)
rope       0.1     20.0       {ea}   -1.0        0    1.2  1.0  0.1   0.0
---------------------- POINTS ---------------------------------------
ID  Attachment  X     Y    Z      Mass  Volume  CdA  Ca
(#) (-)         (m)   (m)  (m)    (kg)  (m^3)   (m2) (-)
1   Fixed       0     0    -40    0     0       0    0
2   Fixed       {x}   0    {z}    0     0       0    0
---------------------- LINES ----------------------------------------
ID  LineType  AttachA  AttachB  UnstrLen  NumSegs  LineOutputs
(#) (name)    (#)      (#)      (m)       (-)      (-)
1   rope      1        2        {length}  {n}      -
---------------------- OPTIONS --------------------------------------
{g}       g
{rho}     WtrDnsty
200       WtrDpth
----------------------- need this line ------------------------------
"""


def _scene(**kw):
    values = dict(ea=1e7, x=60.0, z=-5.0, length=60.0, n=10, g=9.81, rho=1025.0)
    values.update(kw)
    return build_scene(parse_deck(DECK.format(**values)))


def test_weightless_taut_line_tension_is_ea_strain():
    """g = 0: the straight chord is the equilibrium (no interior force) and both
    ends carry EA·(chord/L − 1), exactly."""
    import jax.numpy as jnp

    scene = _scene(g=0.0, length=66.0, n=6)
    assert scene.env.seabed is not None  # weightless, not buoyant: it can still be pushed onto the bed
    line = scene.lines[0]
    r = jnp.linspace(jnp.array([0.0, 0.0, -40.0]), jnp.array([60.0, 0.0, -5.0]), 7)
    f = np.asarray(line.element.nodal_forces(line, scene.env, r, jnp.zeros_like(r)))
    chord = np.hypot(60.0, 35.0)
    expected = 1e7 * (chord / 66.0 - 1.0)
    np.testing.assert_allclose(f[1:-1], 0.0, atol=1e-8 * expected)
    np.testing.assert_allclose([np.linalg.norm(f[0]), np.linalg.norm(f[-1])], expected, rtol=1e-12)


def test_line_in_air_is_moorpys_catenary_with_dry_weight():
    from moorpy.Catenary import catenary

    scene = _scene(rho=0.0, length=70.5, n=40, ea=1e8)
    assert scene.lines[0].line_type.wet_weight(scene.env.rho, scene.env.g) == pytest.approx(20.0 * 9.81)
    st = solve_line_statics(scene.lines[0], scene.env)
    fx, fz, hb, vb = catenary(60.0, 35.0, 70.5, 1e8, 20.0 * 9.81, CB=-1.0)[:4]
    ta = np.hypot(fx, fz)
    tb = np.hypot(hb, vb)
    # MoorPy returns end-A (HA, VA) and end-B (HF, VF) forces; compare magnitudes
    np.testing.assert_allclose(sorted([float(st.tension_a), float(st.tension_b)]), sorted([ta, tb]),
                               rtol=2e-3)


@pytest.mark.parametrize("name, value", [("g", -9.81), ("WtrDnsty", -1.0)])
def test_negative_gravity_or_density_refused(name, value):
    kw = {"g": -9.81} if name == "g" else {"rho": -1.0}
    with pytest.raises(InputError, match=rf"{name} = {value} .* must be >= 0"):
        _scene(**kw)
