"""Waves on lines: the Airy wave model, MoorDyn's ``WaveKin`` decks, and loads.

- :class:`AiryWaves` against linear wave theory (dispersion, the kinematic
  surface condition, deep water, a = ∂u/∂t);
- the wave files of MoorDyn's public decks (``tests/data/public/wavekin_2``:
  ``wavekin_2.txt`` WaveKin 2, ``wavekin_3.txt`` WaveKin 3;
  ``tests/data/public/wavekin_7``: WaveKin 7), and their kinematics against
  MoorDyn 2 run in this process (``moordyn.GetWavesKin``);
- the line loads: zero waves are no waves, the Froude–Krylov/added-mass load
  of a uniform acceleration, statics ignore the waves;
- dynamic runs of ``wavekin_3.txt`` and ``wavekin_7.txt`` against MoorDyn 2
  run in this process (fairlead tension; ``slow``, ~50 s each, mostly the
  compile).
"""

from __future__ import annotations

import os
import shutil
import time
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import moorjax as mj
from moorjax.body.waves import wave_components
from moorjax.io import build_scene, read_deck
from moorjax.io.errors import InputError
from moorjax.io.waves import read_deck_waves
from moorjax.model import AiryWaves, GridAiryWaves, IrregularWave, LineState, wave_number
from moorjax.statics import solve_line_statics

PUBLIC = Path(__file__).parent / "data" / "public"
G = 9.80665


# ----------------------------------------------------------------------------
# the wave model against linear theory
# ----------------------------------------------------------------------------


@pytest.mark.parametrize("omega, depth", [(0.2, 50.0), (0.6, 30.0), (1.5, 200.0), (3.0, 10.0)])
def test_wave_number_solves_the_dispersion_relation(omega, depth):
    k = float(wave_number(omega, depth, G))
    assert abs(G * k * np.tanh(k * depth) - omega**2) < 1e-13 * omega**2
    # implicit derivative: dk/dω = 2ω / (g tanh kh + g kh sech² kh)
    dk = float(jax.grad(lambda w: wave_number(w, depth, G))(omega))
    ref = 2 * omega / (G * np.tanh(k * depth) + G * k * depth / np.cosh(k * depth) ** 2)
    assert abs(dk - ref) < 1e-10 * abs(ref)


def _one(a=1.0, omega=0.5, phase=0.3, heading=0.4, depth=40.0):
    return AiryWaves(IrregularWave(omega, a, phase, heading), depth, G)


def test_finite_depth_kinematics_match_airy_theory():
    a, om, ph, beta, h = 0.8, 0.5, 0.3, 0.4, 40.0
    w = _one(a, om, ph, beta, h)
    k = float(w.k[0])
    rng = np.random.default_rng(0)
    pts = np.c_[rng.uniform(-100, 100, (20, 2)), rng.uniform(-h, -2.0, 20)]
    for t in (0.0, 3.7, 11.2):
        eta, u, acc = (np.asarray(x) for x in w.kinematics(jnp.asarray(pts), t))
        psi = om * t - k * (pts[:, 0] * np.cos(beta) + pts[:, 1] * np.sin(beta)) + ph
        np.testing.assert_allclose(eta, a * np.cos(psi), atol=1e-13)
        zs = h * (pts[:, 2] + h) / (eta + h) - h  # Wheeler stretching (MoorDyn)
        ch, sh = np.cosh(k * (zs + h)) / np.sinh(k * h), np.sinh(k * (zs + h)) / np.sinh(k * h)
        uh, ah = a * om * ch * np.cos(psi), -a * om**2 * ch * np.sin(psi)
        np.testing.assert_allclose(u, np.c_[uh * np.cos(beta), uh * np.sin(beta), -a * om * sh * np.sin(psi)],
                                   atol=1e-12)
        np.testing.assert_allclose(acc, np.c_[ah * np.cos(beta), ah * np.sin(beta),
                                              -a * om**2 * sh * np.cos(psi)], atol=1e-12)


def test_surface_moves_with_the_water_and_points_above_see_the_surface():
    """Kinematic surface condition: at z = η the vertical velocity is ∂η/∂t; a
    point above the surface gets the surface's kinematics (MoorDyn)."""
    w = _one(a=1.5, omega=0.7, heading=0.0)
    x = jnp.linspace(-60.0, 60.0, 7)
    for t in (0.5, 4.0):
        eta = w.elevation(x, 0.0 * x, t)
        r = jnp.stack([x, 0.0 * x, eta], axis=-1)
        _, u, acc = w.kinematics(r, t)
        deta = jax.vmap(jax.grad(lambda tt, xx: w.elevation(xx, 0.0, tt)), (None, 0))(t, x)
        np.testing.assert_allclose(u[:, 2], deta, atol=1e-12)
        _, u_up, a_up = w.kinematics(r.at[:, 2].add(3.0), t)
        np.testing.assert_array_equal(u_up, u)
        np.testing.assert_array_equal(a_up, acc)


def test_deep_water_limit_and_acceleration_is_the_time_derivative():
    # kh = 250: deep water, k = ω²/g, u = aω e^{kz}; small amplitude so stretching is negligible
    a, om, h = 1e-4, 1.5, 1000.0
    w = _one(a, om, 0.0, 0.0, h)
    assert abs(float(w.k[0]) - om**2 / G) < 1e-15
    z = jnp.array([-1.0, -5.0, -20.0])
    r = jnp.stack([0 * z, 0 * z, z], axis=-1)
    eta, u, _ = w.kinematics(r, 0.0)
    zs = h * (np.asarray(z) + h) / (np.asarray(eta) + h) - h  # stretched by η = a
    np.testing.assert_allclose(u[:, 0], a * om * np.exp(om**2 / G * zs), rtol=1e-12)
    # a(t) = du/dt at a fixed point (to the O(a) of the stretching)
    dudt = jax.jacfwd(lambda t: w.kinematics(r, t)[1])(2.0)
    np.testing.assert_allclose(w.kinematics(r, 2.0)[2], dudt, rtol=1e-4, atol=1e-14)


def test_body_and_line_waves_are_one_model():
    """The PM components of the body loads drive the line kinematics unchanged."""
    wave = wave_components(2.0, 8.0, 30, seed=3, heading=0.5)
    airy = AiryWaves(wave, 100.0)
    t = jnp.linspace(0.0, 50.0, 11)
    np.testing.assert_allclose(airy.elevation(jnp.zeros(11), jnp.zeros(11), t), wave.elevation(t), atol=1e-12)
    # a body's loads take one heading; a short-crested component set is refused with the reason
    from moorjax.body.waves import loads_for_wave

    spread = IrregularWave([0.5, 0.6], [1.0, 1.0], [0.0, 0.0], [0.0, 1.0])
    with pytest.raises(ValueError, match="one wave heading"):
        loads_for_wave(None, spread)


# ----------------------------------------------------------------------------
# MoorDyn's wave files
# ----------------------------------------------------------------------------


def test_wave_files_of_the_public_decks_give_moordyn_components():
    # WaveKin 7: rows (0.35, 1 + 0i, 0) and (0.4, 0 + 1i, 1.57): η = Σ|A| sin(ψ + arg A)
    w7 = read_deck(PUBLIC / "wavekin_7" / "wavekin_7.txt").waves
    np.testing.assert_allclose(w7.omega, [0.35, 0.4])
    np.testing.assert_allclose(w7.amplitude, [1.0, 1.0])
    np.testing.assert_allclose(w7.phase, [-np.pi / 2, 0.0], atol=1e-15)
    np.testing.assert_allclose(w7.heading, [0.0, 1.57])
    # WaveKin 2: the spectrum interpolated to 0.05 rad/s steps; η = Σ Re(A e^{iψ})
    w2 = read_deck(PUBLIC / "wavekin_2" / "wavekin_2.txt").waves
    big = w2.amplitude > 1e-9
    np.testing.assert_allclose(w2.omega[big], [0.2, 0.25, 0.4, 0.45])
    np.testing.assert_allclose(w2.amplitude[big], [0.5, 0.2, 1.0, 0.5])
    np.testing.assert_allclose(w2.phase[big], [0, 0, np.pi / 2, np.pi / 2], atol=1e-12)
    # WaveKin 3: η = sin(2πt/15) sampled every dtWave = 0.15 s -> one component
    w3 = read_deck(PUBLIC / "wavekin_2" / "wavekin_3.txt").waves
    main = np.argmax(w3.amplitude)
    assert abs(w3.omega[main] - 2 * np.pi / 15) < 1e-6 and abs(w3.amplitude[main] - 1.0) < 1e-6
    assert abs(w3.phase[main] + np.pi / 2) < 1e-6  # sin = cos(· − π/2)
    assert np.sum(w3.amplitude) - w3.amplitude[main] < 1e-6
    assert w3.grid is not None and w3.grid[2][0] == -51.0


def test_elevation_record_becomes_its_fourier_components(tmp_path):
    """WaveKin 3 semantics: samples at dtWave (an odd count loses its last), the
    mean as a level, 2X_j/N components, bins above 0.5 Hz cut."""
    shutil.copy(PUBLIC / "wavekin_2" / "water_grid.txt", tmp_path / "water_grid.txt")
    dt, n = 0.25, 81  # 81 samples -> 80 used: T = 20 s, Δω = 2π/20 rad/s
    t = np.arange(n) * dt
    w1, w_hi = 3 * 2 * np.pi / 20, 16 * 2 * np.pi / 20  # 0.15 Hz kept, 0.8 Hz cut
    eta = 0.3 + 0.5 * np.cos(w1 * t + 0.4) + 0.2 * np.cos(w_hi * t - 1.0)
    (tmp_path / "wave_elevation.txt").write_text("".join(f"{a:.17g} {b:.17g}\n" for a, b in zip(t, eta)))
    w = read_deck_waves(tmp_path, 3, dt)
    assert abs(w.mean_level - 0.3) < 1e-12
    big = w.amplitude > 1e-9
    np.testing.assert_allclose(w.omega[big], [w1], rtol=1e-12)
    np.testing.assert_allclose(w.amplitude[big], [0.5], rtol=1e-9)
    np.testing.assert_allclose(w.phase[big], [0.4], atol=1e-9)
    assert np.max(w.omega) <= np.pi  # nothing above 0.5 Hz


def test_spectrum_rows_with_directions_and_a_constant_level(tmp_path):
    (tmp_path / "wave_frequencies.txt").write_text("0.0 0.0 0.25\n0.5 0.0 2.0 1.0\n0.5 1.0 0.0 -0.5\n")
    w = read_deck_waves(tmp_path, 7)  # repeated frequencies in two directions: mode 7 only
    assert w.mean_level == 0.25  # |A| sin(arg A) of the 0 rad/s row
    np.testing.assert_allclose(w.amplitude, [2.0, 1.0])
    np.testing.assert_allclose(w.heading, [1.0, -0.5])
    with pytest.raises(InputError, match="must increase strictly for WaveKin = 2"):
        shutil.copy(PUBLIC / "wavekin_2" / "water_grid.txt", tmp_path / "water_grid.txt")
        read_deck_waves(tmp_path, 2)


def test_vmap_over_sea_states_equals_a_loop():
    line, _ = _line()
    r = jnp.asarray(np.linspace([-15.0, 0, -20], [14.0, 0, -12], 7))
    v = jnp.zeros_like(r)

    def force(amp, phase):
        env = mj.Environment(60.0, seabed=mj.Seabed(), waves=AiryWaves(IrregularWave(0.6, amp, phase), 60.0))
        return line.element.nodal_forces(line, env, r, v, 1.3)

    amps, phases = jnp.array([0.0, 0.5, 1.5]), jnp.array([0.0, 1.0, 2.0])
    batched = jax.vmap(force)(amps, phases)
    for i in range(3):
        np.testing.assert_allclose(batched[i], force(amps[i], phases[i]), rtol=1e-12, atol=1e-9)


def _deck(tmp_path, wavekin, files):
    src = (PUBLIC / "wavekin_2" / "wavekin_3.txt").read_text()
    deck = tmp_path / "d.txt"
    deck.write_text(src.replace("3             WaveKin", f"{wavekin}             WaveKin")
                    .replace("1             Currents", "0             Currents"))
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    return deck


@pytest.mark.parametrize("mode, msg", [
    (4, "not implemented in MoorDyn v2 either"),
    (9, "not a MoorDyn wave mode"),
])
def test_unsupported_wave_modes_are_refused(tmp_path, mode, msg):
    with pytest.raises(InputError, match=rf"d.txt:\d+: OPTIONS: WaveKin = {mode}:? .*{msg}"):
        read_deck(_deck(tmp_path, mode, {}))


def test_wave_file_errors_name_the_file_and_the_fix(tmp_path):
    with pytest.raises(InputError, match=r"WaveKin = 7: the wave file .*wave_frequencies.txt' does not exist"):
        read_deck(_deck(tmp_path, 7, {}))
    with pytest.raises(InputError, match=r"wave_frequencies.txt:1: the first frequency is 0.1 rad/s"):
        read_deck(_deck(tmp_path, 7, {"wave_frequencies.txt": "0.1 1 0\n0.2 1 0\n"}))
    with pytest.raises(InputError, match=r"wave_frequencies.txt:2: 2 numbers; expected 3 or 4"):
        read_deck(_deck(tmp_path, 7, {"wave_frequencies.txt": "0 0 0\n0.2 1\n"}))
    with pytest.raises(InputError, match=r"water_grid.txt' does not exist"):
        read_deck(_deck(tmp_path, 3, {"wave_elevation.txt": "0 0\n1 1\n"}))


def test_points_outside_moordyns_wave_grid_are_warned(tmp_path):
    dest = tmp_path / "w"
    shutil.copytree(PUBLIC / "wavekin_2", dest)
    grid = (dest / "water_grid.txt").read_text().splitlines()
    grid[3:5] = ["2", "-300 50 351"]  # x from -300 m: the anchor (x = -400 m) is outside
    (dest / "water_grid.txt").write_text("\n".join(grid) + "\n")
    with pytest.warns(mj.io.InputWarning, match=r"points \[1\] lie outside the x/y extent of water_grid"):
        build_scene(read_deck(dest / "wavekin_3.txt"))


def test_elevation_series_error_is_named(tmp_path):
    shutil.copy(PUBLIC / "wavekin_2" / "water_grid.txt", tmp_path / "water_grid.txt")
    (tmp_path / "wave_elevation.txt").write_text("0 0\n1 1\n0.5 0\n")
    with pytest.raises(InputError, match=r"wave_elevation.txt:3: t = 0.5 s is not after"):
        read_deck_waves(tmp_path, 3, 0.1)


# ----------------------------------------------------------------------------
# against MoorDyn 2's kinematics, in this process
# ----------------------------------------------------------------------------


def _moordyn_copy(tmp_path, folder, deck):
    dest = tmp_path / folder
    shutil.copytree(PUBLIC / folder, dest)
    if folder == "wavekin_2":
        # its waves all travel along +x: one y in the grid (kind 0) builds MoorDyn's
        # grid 5 times faster and changes nothing (MoorDyn holds y at the nearest)
        grid = (dest / "water_grid.txt").read_text().splitlines()
        grid[5:7] = ["0", "0.0"]
        (dest / "water_grid.txt").write_text("\n".join(grid) + "\n")
    return dest / deck


@pytest.mark.parametrize("folder, deck, tol", [
    ("wavekin_7", "wavekin_7.txt", 1e-9),  # the same sum: MoorDyn's 7-digit wave number only
    ("wavekin_2", "wavekin_3.txt", 1e-3),  # MoorDyn interpolates a (x, z, t) grid, dt = 0.15 s
    ("wavekin_2", "wavekin_2.txt", 1e-2),  # grid dt = 2π/Δω/n = 0.52 s
])
def test_kinematics_match_moordyn(tmp_path, folder, deck, tol):
    moordyn = pytest.importorskip("moordyn")
    path = _moordyn_copy(tmp_path, folder, deck)
    cwd = os.getcwd()
    os.chdir(path.parent)  # MoorDyn finds its wave files beside the deck
    try:
        s = moordyn.Create(str(path))
        n_dof = 3 if folder == "wavekin_7" else 0
        moordyn.Init(s, [0.0] * n_dof, [0.0] * n_dof)
        waves = moordyn.GetWaves(s)
        env = build_scene(read_deck(path)).env
        assert isinstance(env.waves, GridAiryWaves) == (folder == "wavekin_2")
        pts = np.array([[-100.0, 0.5, -20.0], [-10.0, -1.0, -2.0], [-350.2, 0.0, -45.0],
                        [-200.5, 0.0, -10.3], [-5.0, 0.0, 2.5]])  # the last above the surface
        t, worst = 0.0, 0.0
        for _ in range(3):
            moordyn.Step(s, [0.0] * n_dof, [0.0] * n_dof, t, 1.37)
            t += 1.37
            for p in pts:
                u, ud, zeta, _ = moordyn.GetWavesKin(waves, *p)
                eta, uj, aj = env.waves.kinematics(jnp.asarray(p), t)
                if env.current is not None:
                    uj = uj + env.current.velocity(env.waves.current_height(jnp.asarray(p), eta), t)
                worst = max(worst, np.max(np.abs(np.asarray(u) - uj)), np.max(np.abs(np.asarray(ud) - aj)),
                            abs(zeta - float(eta)))
        moordyn.Close(s)
    finally:
        os.chdir(cwd)
    print(f"{deck}: largest difference of u [m/s], a [m/s²], η [m] from MoorDyn: {worst:.2e}")
    assert worst < tol, worst


# ----------------------------------------------------------------------------
# line loads
# ----------------------------------------------------------------------------


def _line(n=6, added=True, drag=True, depth=60.0, waves=None, current=None):
    lt = mj.LineType(0.1, 20.0, 5e7, 0.0, mj.MorisonDrag(1.2, 0.2) if drag else None,
                     mj.AddedMass(0.9, 0.3) if added else None)
    env = mj.Environment(depth, seabed=mj.Seabed(), current=current, waves=waves)
    line = mj.Line(lt, 30.0, n, mj.FixedEnd([-15.0, 0.0, -20.0]), mj.FixedEnd([14.0, 0.0, -12.0]))
    return line, env


def test_zero_amplitude_waves_are_no_waves():
    zero = AiryWaves(IrregularWave([0.4, 0.9], [0.0, 0.0], [0.1, 2.0], [0.0, 1.0]), 60.0)
    cur = mj.UniformCurrent([0.3, 0.1, 0.0])
    line, env = _line(waves=zero, current=cur)
    _, still = _line(current=cur)
    rng = np.random.default_rng(1)
    r = jnp.asarray(np.linspace([-15.0, 0, -20], [14.0, 0, -12], 7) + rng.normal(0, 0.3, (7, 3)))
    v = jnp.asarray(rng.normal(0, 0.5, (7, 3)))
    f_wave = line.element.nodal_forces(line, env, r, v, 3.0)
    f_still = line.element.nodal_forces(line, still, r, v, 3.0)
    np.testing.assert_allclose(f_wave, f_still, rtol=0, atol=1e-12 * float(jnp.max(jnp.abs(f_still))))


def test_froude_krylov_load_of_a_nearly_uniform_acceleration():
    """A short straight line deep under a long wave: the water's acceleration a is
    nearly uniform along it, and the wave load is ρAL[(1 + Ca_n)a_n + (1 + Ca_ax)a_t]."""
    waves = AiryWaves(IrregularWave(0.3, 0.5, 0.0), 60.0)
    line, env = _line(n=8, drag=False, waves=waves)
    r = jnp.asarray(np.linspace([-0.15, 0.0, -20.0], [0.15, 0.0, -19.6], 9))  # 0.5 m long
    v = jnp.zeros_like(r)
    _, still = _line(n=8, drag=False)
    f = jnp.sum(line.element.nodal_forces(line, env, r, v, 2.0) - line.element.nodal_forces(line, still, r, v, 2.0),
                axis=0)
    _, _, acc = waves.kinematics(r, 2.0)
    a = np.asarray(jnp.mean(acc, axis=0))
    d = np.asarray(r[-1] - r[0])
    length = np.linalg.norm(d)
    t = d / length
    at = np.dot(a, t) * t
    lt = line.line_type
    ref = 1025.0 * float(lt.area) * length * ((1 + 0.9) * (a - at) + (1 + 0.3) * at)
    np.testing.assert_allclose(f, ref, rtol=1e-3)
    assert np.linalg.norm(ref) > 0.1  # [N] on 0.5 m of 0.1 m line


def test_free_point_drag_sees_the_wave_velocity():
    """A free point at rest under a wave: the wave adds the drag ½ρ·CdA·|u_w|u_w
    (MoorDyn's Point; like MoorDyn, no load from the water's acceleration)."""
    from moorjax.body.point import ConnectionPoint

    waves = AiryWaves(IrregularWave(0.5, 1.0, 0.3, 0.7), 60.0)
    point = ConnectionPoint(200.0, [3.0, 1.0, -8.0], volume=0.1, added_mass=50.0, cda=0.8,
                            current=mj.UniformCurrent([0.2, 0.0, 0.0]))
    z = point.rest_state()
    env = mj.Environment(60.0, waves=waves)
    still = mj.Environment(60.0)
    t = 2.5
    extra = (point.rate(t, z, jnp.zeros(6), env) - point.rate(t, z, jnp.zeros(6), still))[6:9] * 250.0
    _, u_wave, _ = waves.kinematics(point.origin, t)
    u = u_wave + jnp.array([0.2, 0.0, 0.0])
    ref = 0.5 * 1025.0 * 0.8 * (jnp.linalg.norm(u) * u - 0.2 * jnp.array([0.2, 0.0, 0.0]))
    np.testing.assert_allclose(extra, ref, rtol=1e-10)
    assert float(jnp.linalg.norm(u_wave)) > 0.3


def test_statics_solve_the_mean_state_without_waves():
    waves = AiryWaves(IrregularWave([0.5, 0.8], [2.0, 1.0], [0.0, 1.0]), 60.0)
    line, env = _line(waves=waves, current=mj.UniformCurrent([0.5, 0.0, 0.0]))
    _, still = _line(current=mj.UniformCurrent([0.5, 0.0, 0.0]))
    st = solve_line_statics(line, env)
    r = st.positions
    v = jnp.zeros_like(r)
    scale = float(jnp.max(st.tensions))
    # balanced in the still water (with the current) ...
    assert float(jnp.max(jnp.abs(line.element.nodal_forces(line, still, r, v)[1:-1]))) < 1e-6 * scale
    # ... and not under the waves of t = 0, which statics ignore (as MoorDyn's initial condition)
    assert float(jnp.max(jnp.abs(line.element.nodal_forces(line, env, r, v, 0.0)[1:-1]))) > 1e-3 * scale


def test_wave_force_gradient_matches_finite_differences():
    def force(amp):
        waves = AiryWaves(IrregularWave(0.6, amp, 0.2, 0.3), 60.0)
        line, env = _line(waves=waves)
        r = jnp.asarray(np.linspace([-15.0, 0, -20], [14.0, 0, -12], 7))
        return jnp.sum(line.element.nodal_forces(line, env, r, jnp.zeros_like(r), 1.3)[3] ** 2)

    g = float(jax.grad(force)(1.2))
    h = 1e-4
    fd = (float(force(1.2 + h)) - float(force(1.2 - h))) / (2 * h)
    assert abs(g - fd) < 1e-6 * abs(fd) and abs(fd) > 0


# ----------------------------------------------------------------------------
# dynamics against MoorDyn 2
# ----------------------------------------------------------------------------


def _moordyn_tension(moordyn, path, n_dof, duration):
    """MoorDyn 2's initial nodes, and its fairlead tension every 0.05 s [N]."""
    cwd = os.getcwd()
    os.chdir(path.parent)  # MoorDyn finds its wave files beside the deck
    try:
        t0 = time.perf_counter()
        s = moordyn.Create(str(path))
        moordyn.Init(s, [0.0] * n_dof, [0.0] * n_dof)
        ln = moordyn.GetLine(s, 1)
        n = moordyn.GetLineN(ln)
        r0 = np.array([moordyn.GetLineNodePos(ln, k) for k in range(n + 1)])
        t1 = time.perf_counter()
        ts, ref = [], []
        t, dt = 0.0, 0.05
        while t < duration - 1e-9:
            moordyn.Step(s, [0.0] * n_dof, [0.0] * n_dof, t, dt)
            t += dt
            ts.append(t)
            ref.append(np.linalg.norm(moordyn.GetLineNodeTen(ln, n)))
        moordyn.Close(s)
    finally:
        os.chdir(cwd)
    return r0, np.asarray(ts), np.asarray(ref), t1 - t0, time.perf_counter() - t1


@pytest.mark.slow
@pytest.mark.parametrize("folder, deck, n_dof, duration, settled", [
    # a 410 m chain on a soft seabed, both ends fixed (fairlead 2 m under the still
    # surface), a 1 m, 15 s wave given as an elevation record (WaveKin 3) and a
    # depth-varying current; the last wave period, after the start-up transient on
    # the seabed (MoorDyn's TmaxIC = 0 starts from its catenary guess)
    ("wavekin_2", "wavekin_3.txt", 0, 45.0, 30.0),
    # a light 410 m chain to a fairlead at the surface, two 1 m waves (0.35 rad/s
    # along x, 0.4 rad/s along y) summed at the nodes (WaveKin 7)
    ("wavekin_7", "wavekin_7.txt", 3, 20.0, 0.0),
])
def test_fairlead_tension_in_waves_matches_moordyn(tmp_path, folder, deck, n_dof, duration, settled):
    """From MoorDyn's initial state, moorjax and MoorDyn 2 (run here) in the
    deck's waves: fairlead tension every 0.05 s after ``settled`` [s]."""
    moordyn = pytest.importorskip("moordyn")
    from moorjax.dynamics import simulate

    path = _moordyn_copy(tmp_path, folder, deck)
    r0, ts, ref, t_init, t_md = _moordyn_tension(moordyn, path, n_dof, duration)
    n = r0.shape[0] - 1
    scene = build_scene(read_deck(path))
    # MoorDyn's seabed damping law (no ramp: the start-up transient sinks the line into the bed)
    scene = eqx.tree_at(lambda sc: sc.env.seabed.damping_depth, scene, jnp.asarray(0.0),
                        is_leaf=lambda x: x is None)
    init = (LineState(r=jnp.asarray(r0[1:-1]), v=jnp.zeros((n - 1, 3))),)
    t2 = time.perf_counter()
    res = simulate(scene, ts=ts, init=init, rtol=1e-5, atol=1e-4, save_nodes=True)
    tens = np.asarray(res.segment_tensions[0])[:, -1]
    t_mj = time.perf_counter() - t2
    t3 = time.perf_counter()
    jax.block_until_ready(simulate(scene, ts=ts, init=init, rtol=1e-5, atol=1e-4, save_nodes=True).tension_b)
    t_warm = time.perf_counter() - t3
    last = ts > settled
    err = np.sqrt(np.mean((tens[last] - ref[last]) ** 2))
    std = np.std(ref[last])
    print(f"{deck}: fairlead tension {settled:g}-{duration:g} s: RMS error {err:.1f} N, MoorDyn std {std:.1f} N "
          f"({err / std:.1%}); {duration:g} s of MoorDyn {t_md:.2f} s (+{t_init:.2f} s init/grid), moorjax "
          f"{t_warm:.2f} s (first call with compile {t_mj:.1f} s)")
    # the waves swing the tension (without them it is flat to 0.003 % here, std 26 N and 0.1 N)
    assert std > 0.004 * np.mean(ref[last])
    assert err < 0.1 * std, (err, std)
