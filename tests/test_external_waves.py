"""MoorDyn's ``WaveKin = 1``: wave kinematics supplied at run time.

MoorDyn takes them through its API (``ExternalWaveKinSet``, held until the next
call); moorjax takes the function itself (:class:`moorjax.model.ExternalWaves`,
``build_scene(..., waves=...)``, ``--wave-kinematics FILE.py:NAME``).

Data (``tests/data/wavekin_1/``, see its README entry): MoorDyn's
``wavekin_current_1.txt`` unchanged (it reads and, without kinematics, runs in
still water), and ``line.dat``, a chain hung clear of the seabed with
``WaveKin = 1``, with MoorDyn 2.7.2 histories under the two functions of
``kinematics.py`` (a uniform 1 m/s current, MoorDyn's own ``tests/wavekin.cpp``
callback, and a regular Airy wave), set every 0.01 s.
"""

import importlib.util
import json
import subprocess
import sys
import time
from pathlib import Path

import jax.numpy as jnp
import numpy as np
import pytest

from moorjax.dynamics import simulate
from moorjax.io import InputError, InputWarning, build_scene, read_deck
from moorjax.model import AiryWaves, Environment, ExternalWaves, IrregularWave, LineState

DATA = Path(__file__).parent / "data" / "wavekin_1"


def _kinematics():
    spec = importlib.util.spec_from_file_location("wavekin_1_kinematics", DATA / "kinematics.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_public_deck_reads_and_warns_that_the_water_is_still():
    deck = read_deck(DATA / "wavekin_current_1.txt")
    with pytest.warns(InputWarning, match="WaveKin = 1.*none were given, so the water is still"):
        scene = build_scene(deck)
    assert scene.env.waves is None
    scene = build_scene(deck, waves=ExternalWaves(_kinematics().current))
    assert isinstance(scene.env.waves, ExternalWaves)


def test_external_kinematics_refused_for_a_deck_with_its_own_waves():
    deck = read_deck(Path(__file__).parent / "data" / "current_steady" / "line.dat")  # WaveKin 0
    with pytest.raises(InputError, match="set WaveKin to 1"):
        build_scene(deck, waves=ExternalWaves(_kinematics().current))
    with pytest.raises(ValueError, match="needs a function"):
        ExternalWaves(3.0)


def test_external_waves_equal_airy_waves_given_the_same_function():
    """ExternalWaves of AiryWaves' own kinematics (and elevation) is AiryWaves: the
    same velocity, acceleration and surface wherever the physics samples them."""
    wave = IrregularWave([0.5, 0.9], [1.2, 0.4], [0.3, -1.0], [0.0, 0.4])
    airy = AiryWaves(wave, 50.0)
    ext = ExternalWaves(lambda r, t: airy.kinematics(r, t)[1:], lambda x, y, t: airy.elevation(x, y, t))
    r = jnp.asarray(np.random.default_rng(0).uniform([-50, -50, -50], [50, 50, 2], (40, 3)))
    for t in (0.0, 3.7):
        for a, b in zip(ext.kinematics(r, t), airy.kinematics(r, t)):
            np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=1e-13, atol=1e-13)
    # and through a short run of the test deck (surface, drag, water acceleration)
    deck = read_deck(DATA / "line.dat")
    runs = []
    for waves in (airy, ext):
        scene = build_scene(deck, segments=6, waves=waves)
        res = simulate(scene, ts=np.array([0.5, 1.0]), save_nodes=True)
        runs.append(np.asarray(res.segment_tensions[0]))
    np.testing.assert_allclose(runs[0], runs[1], rtol=1e-9)


def test_environment_accepts_any_wave_kinematics_and_refuses_others():
    Environment(50.0, waves=ExternalWaves(_kinematics().wave))
    with pytest.raises(ValueError, match="AbstractWaveKinematics"):
        Environment(50.0, waves=_kinematics().wave)


def _against_moordyn(name, every):
    ref = json.loads((DATA / f"moordyn_{name}.json").read_text())
    scene = build_scene(read_deck(DATA / "line.dat"), waves=ExternalWaves(getattr(_kinematics(), name)))
    r0 = np.asarray(ref["initial"]["lines"][0]["positions"])  # MoorDyn's initial condition
    init = (LineState(r=jnp.asarray(r0[1:-1]), v=jnp.zeros((len(r0) - 2, 3))),)
    hist = ref["history"]
    ts = np.asarray(hist["t"])[every - 1::every]
    t0 = time.perf_counter()
    res = simulate(scene, ts=ts, init=init, save_nodes=True)
    wall = time.perf_counter() - t0
    mid = np.asarray(res.positions[0])[:, 10]
    mid_ref = np.asarray(hist["mid"])[every - 1::every, 0]
    travel = np.max(np.linalg.norm(mid_ref - r0[10], axis=1))
    err = np.max(np.linalg.norm(mid - mid_ref, axis=1))
    tb = np.asarray(res.segment_tensions[0])[:, -1]
    tb_ref = np.asarray(hist["tension_b"])[every - 1::every, 0]
    return ts, err, travel, tb, tb_ref, wall


@pytest.mark.slow
def test_uniform_external_current_matches_moordyn():
    """MoorDyn's own callback (1 m/s along +x): the chain swings 0.8 m out of its plane."""
    ts, err, travel, tb, tb_ref, wall = _against_moordyn("current", 10)
    print(f"WaveKin = 1, uniform 1 m/s, {ts[-1]:g} s: mid-node error {err * 1e3:.2f} mm of {travel:.3f} m "
          f"travel ({err / travel:.2%}); fairlead tension within {np.max(np.abs(tb / tb_ref - 1)):.2e}; "
          f"moorjax {wall:.1f} s with compilation")
    assert travel > 0.5
    assert err < 0.01 * travel, (err, travel)
    np.testing.assert_allclose(tb, tb_ref, rtol=2e-3)  # axial ringing of the stiff chain, both codes


@pytest.mark.slow
def test_external_regular_wave_matches_moordyn():
    """A regular 8 s wave given as a function; MoorDyn holds it for 0.01 s at a time."""
    ts, err, travel, tb, tb_ref, wall = _against_moordyn("wave", 4)
    rms = np.sqrt(np.mean((tb - tb_ref) ** 2)) / np.std(tb_ref)
    print(f"WaveKin = 1, regular wave, {ts[-1]:g} s: mid-node error {err * 1e3:.2f} mm of {travel:.3f} m "
          f"travel ({err / travel:.2%}); fairlead tension RMS error {rms:.3f} of its std "
          f"{np.std(tb_ref):.0f} N; moorjax {wall:.1f} s with compilation")
    assert travel > 0.2
    assert err < 0.02 * travel, (err, travel)
    assert rms < 0.2, rms


def test_cli_wave_kinematics_option(tmp_path):
    """``moorjax simulate DECK --wave-kinematics FILE.py:NAME``; a bad spec is one clear line."""
    kin = f"{DATA / 'kinematics.py'}:current"
    out = tmp_path / "run.csv"
    base = [sys.executable, "-m", "moorjax", "simulate", str(DATA / "line.dat"), "--duration", "0.5",
            "--segments", "4", "--quiet"]
    done = subprocess.run(base + ["--wave-kinematics", kin, "--out", str(out)], capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert out.exists()
    bad = subprocess.run(base + ["--wave-kinematics", f"{DATA / 'kinematics.py'}:nothing", "--out", str(out)],
                         capture_output=True, text=True, timeout=600)
    assert bad.returncode != 0
    assert "defines no 'nothing'" in bad.stderr


def test_wave_kinematics_option_errors_name_the_problem(tmp_path):
    """``--wave-kinematics`` parsing (``moorjax._cli_load.wave_kinematics_from``)."""
    from moorjax._cli_load import wave_kinematics_from

    assert wave_kinematics_from(None) is None
    ok = wave_kinematics_from(f"{DATA / 'kinematics.py'}:wave")
    assert isinstance(ok, ExternalWaves)
    broken = tmp_path / "broken.py"
    broken.write_text("import no_such_module_here\n")
    values = tmp_path / "values.py"
    values.write_text("speed = 3.0\nfrom moorjax.model import ExternalWaves\n"
                      "field = ExternalWaves(lambda r, t: (r * 0, r * 0))\n")
    assert isinstance(wave_kinematics_from(f"{values}:field"), ExternalWaves)  # an instance as is
    for spec, msg in ((str(DATA / "kinematics.py"), "expected FILE.py:NAME"),
                      (f"{tmp_path / 'missing.py'}:f", "no such file"),
                      (f"{broken}:f", "importing .* failed: ModuleNotFoundError"),
                      (f"{values}:nothing", "defines no 'nothing'"),
                      (f"{values}:speed", "'speed' is a float, not a function")):
        with pytest.raises(ValueError, match=msg):
            wave_kinematics_from(spec)
