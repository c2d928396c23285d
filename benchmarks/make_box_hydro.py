"""Hydrodynamic database of Wu et al.'s floating box (Table 1) with Capytaine.

    pip install -e .[hydro]        # capytaine
    python benchmarks/make_box_hydro.py --out moorjax/examples/data/wu_box_hydro.npz

The body (Wu et al. Table 1): a 45 m × 45 m box, height 27.5 m, draft 20 m, in
80 m of water (finite depth), ρ = 1025 kg/m³, g = 9.81 m/s². Mass 41,512 t
(= ρ·V: the box floats freely at its 20 m draft). The paper does not give the
centre of gravity: it is taken at the box's geometric centre,
z_G = −20 + 27.5/2 = −6.25 m, on the vertical axis (x_G = y_G = 0). The moments of
inertia of Table 1 (Ixx 4.5316e10, Iyy 4.2748e10, Izz 4.8877e10 kg·m²) are taken
about the CoG. All coefficients refer to the CoG (Capytaine's rotation centre).

What is computed, and how:

- Only the wetted hull (z ≤ 0) is meshed: ``mesh_parallelepiped`` with the top
  missing and xz/yz reflection symmetry (default 18 × 18 × 8 faces: 900 panels,
  2.5 m; ≥ 6 panels per wavelength at 2 rad/s), plus an interior lid at
  ``--lid-z`` (default −0.5 m; 676 panels of ≤ 1.25 m radius) that removes the
  irregular frequencies (the first is near 1.0 rad/s for this box: without the lid
  B33 turns negative there; with a lid as coarse as the hull, spikes remained,
  e.g. B33 at 1.65 rad/s, the (4, 0) sloshing mode of the interior).
  Capytaine's default BEM (Delhommeau Green function, indirect method, which
  also gives the Kochin functions for the drift force).
- Hydrostatics are analytic (exact for a box): C33 = ρgA_wp,
  C44 = C55 = ρg(I_wp + V z_B) − m g z_G; Capytaine's values are printed for
  comparison (its C44, C55 are 0.55 % lower: its one-point panel quadrature of
  ∫y² dA_wp misses A_wp·h²/12 for panels of width h = 2.5 m).
- A(ω), B(ω), excitation X(ω, β) (diffraction + Froude–Krylov) at 45 frequencies
  0.05–2.0 rad/s (step 0.025 rad/s up to 0.3, then 0.05) and headings 0°–180°
  every 15°. X is conjugated into moorjax's e^{+iωt} convention (Capytaine uses
  e^{−iωt}); phases refer to the incident elevation at the origin (x, y) = (0, 0),
  which is the CoG's horizontal position.
- A∞: Capytaine at ω = ∞ (φ = 0 on the free surface) on the hull *without* the
  lid (a lid close to the surface makes that problem ill-conditioned; irregular
  frequencies are a finite-frequency effect). The Ogilvie estimate
  A∞ ≈ A(ω) − Im K̂_fit(ω)/ω from the fitted radiation model (which only sees
  B(ω)) is printed as a consistency check: it agrees to 0.5 % (surge, sway),
  0.6 % (heave), 0.1 % (roll, pitch, yaw).
- Mean drift D(ω, β): Capytaine's far-field (Maruo/Newman momentum) formula from
  the Kochin functions of the diffracted and radiated waves, with the RAO of the
  *freely floating* box (mass and inertia above, no mooring). Potential flow
  alone leaves roll and pitch almost undamped at their resonances (T ≈ 31 s),
  where the drift then spikes (×10⁴ at one frequency); the RAO used here adds a
  viscous roll and pitch damping of ``--rao-damping`` (default 5 %) of critical,
  a usual allowance for a sharp-cornered box. The drift still peaks at the heave
  resonance (ω ≈ 0.55 rad/s, ~1.4 × the reflection limit ½ρgB), which radiation
  damps. Capytaine gives surge, sway and yaw only; heave, roll and pitch drift
  are set to 0 (negligible for the mooring). It is the diagonal (same heading,
  same frequency) of the difference-frequency QTF, per unit amplitude squared.

Prints the sanity checks (natural periods, surge added mass / ρV, drift against
the full-reflection limit ½ρgB) and the run time.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import moorjax  # noqa: E402,F401  (float64)
from moorjax.body.hydro import HydroCoefficients, fit_radiation, save_hydro  # noqa: E402

LENGTH, WIDTH, HEIGHT, DRAFT = 45.0, 45.0, 27.5, 20.0
DEPTH, RHO, G = 80.0, 1025.0, 9.81
MASS = 41512e3
INERTIA = (4.5316e10, 4.2748e10, 4.8877e10)
COG = (0.0, 0.0, -DRAFT + HEIGHT / 2)


def default_omegas():
    return np.round(np.concatenate([np.arange(0.05, 0.30, 0.025), np.arange(0.30, 2.0001, 0.05)]), 6)


def analytic_hydrostatics():
    awp = LENGTH * WIDTH
    vol = awp * DRAFT
    zb = -DRAFT / 2
    c = np.zeros((6, 6))
    c[2, 2] = RHO * G * awp
    c[3, 3] = RHO * G * (LENGTH * WIDTH**3 / 12 + vol * zb) - MASS * G * COG[2]
    c[4, 4] = RHO * G * (WIDTH * LENGTH**3 / 12 + vol * zb) - MASS * G * COG[2]
    return c, vol


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True, help="output .npz path")
    ap.add_argument("--resolution", type=int, nargs=3, default=(18, 18, 8), metavar=("NX", "NY", "NZ"),
                    help="faces along x, y, z of the wetted box (default 18 18 8)")
    ap.add_argument("--lid-z", type=float, default=-0.5, help="z of the irregular-frequency lid [m]")
    ap.add_argument("--lid-panel-radius", type=float, default=1.25,
                    help="largest lid panel radius [m] (a lid as coarse as the hull left spikes in B)")
    ap.add_argument("--headings-deg", type=float, nargs="+", default=list(np.arange(0.0, 180.1, 15.0)))
    ap.add_argument("--n-theta", type=int, default=120, help="Kochin angles over 2π (drift force)")
    ap.add_argument("--rao-damping", type=float, default=0.05,
                    help="viscous roll and pitch damping of the drift RAO, fraction of critical")
    ap.add_argument("--quick", action="store_true", help="few frequencies (a smoke test)")
    args = ap.parse_args(argv)

    import capytaine as cpt
    import xarray as xr
    from capytaine.post_pro import far_field_mean_drift_force, rao

    cpt.set_logging("ERROR")
    t_start = time.perf_counter()
    omegas = default_omegas()
    if args.quick:
        omegas = omegas[::6]
    headings = np.radians(np.asarray(args.headings_deg, dtype=float))

    mesh = cpt.mesh_parallelepiped(size=(LENGTH, WIDTH, DRAFT), center=(0.0, 0.0, -DRAFT / 2),
                                   resolution=tuple(args.resolution), missing_sides={"top"},
                                   reflection_symmetry=True)
    lid = mesh.generate_lid(z=args.lid_z, faces_max_radius=args.lid_panel_radius)
    dofs = cpt.rigid_body_dofs(rotation_center=COG)
    body = cpt.FloatingBody(mesh=mesh, lid_mesh=lid, dofs=dofs, center_of_mass=COG, mass=MASS, name="wu_box")
    hull = cpt.FloatingBody(mesh=mesh, dofs=cpt.rigid_body_dofs(rotation_center=COG), center_of_mass=COG,
                            mass=MASS, name="wu_box_no_lid")
    print(f"mesh: {mesh.nb_faces} hull panels + {lid.nb_faces} lid panels at z = {args.lid_z} m")

    c_hs, volume = analytic_hydrostatics()
    c_capy = body.compute_hydrostatic_stiffness(rho=RHO, g=G).values
    print(f"hydrostatics (analytic | Capytaine): C33 {c_hs[2, 2]:.5e} | {c_capy[2, 2]:.5e} N/m, "
          f"C44 {c_hs[3, 3]:.5e} | {c_capy[3, 3]:.5e}, C55 {c_hs[4, 4]:.5e} | {c_capy[4, 4]:.5e} N·m/rad; "
          f"V = {volume:.1f} (mesh {mesh.disp_volume:.1f}) m³, ρV = {RHO * volume / 1e3:.1f} t")
    if not (c_hs[3, 3] > 0 and c_hs[4, 4] > 0):
        raise SystemExit("the box is unstable in roll/pitch with this CoG")

    dtheta = 2 * np.pi / args.n_theta
    theta = np.concatenate([[-dtheta], np.linspace(0.0, 2 * np.pi, args.n_theta + 1), [2 * np.pi + dtheta]])
    test_matrix = xr.Dataset(coords={
        "omega": omegas, "wave_direction": headings, "radiating_dof": list(body.dofs),
        "water_depth": [DEPTH], "rho": [RHO], "g": [G], "theta": theta})
    solver = cpt.BEMSolver()
    t0 = time.perf_counter()
    ds = solver.fill_dataset(test_matrix, body, progress_bar=False)
    t_bem = time.perf_counter() - t0
    print(f"BEM: {len(omegas)} frequencies × ({len(body.dofs)} radiation + {len(headings)} "
          f"diffraction) problems in {t_bem:.1f} s")

    t0 = time.perf_counter()
    pbs = [cpt.RadiationProblem(body=hull, radiating_dof=d, omega=np.inf, water_depth=DEPTH, rho=RHO, g=G)
           for d in hull.dofs]
    a_inf = cpt.assemble_dataset(solver.solve_all(pbs, progress_bar=False)).added_mass.values.squeeze()
    print(f"A∞ (ω = ∞, hull without lid) in {time.perf_counter() - t0:.1f} s")

    # drift: far-field formula with the RAO of the freely floating box
    dof_names = list(body.dofs)
    mass_matrix = np.diag([MASS, MASS, MASS, *INERTIA])

    def dof_matrix(m):
        return xr.DataArray(m, dims=["influenced_dof", "radiating_dof"],
                            coords={"influenced_dof": dof_names, "radiating_dof": dof_names})

    ds["inertia_matrix"] = dof_matrix(mass_matrix)
    ds["hydrostatic_stiffness"] = dof_matrix(c_hs)
    # viscous roll/pitch damping ζ·2√((I + A(ω_n))·C) for the RAO only (see docstring)
    visc = np.zeros((6, 6))
    om_all = ds.omega.values
    a_diag = ds.added_mass.transpose("omega", "influenced_dof", "radiating_dof").values
    for k in (3, 4):
        w = np.sqrt(c_hs[k, k] / mass_matrix[k, k])
        for _ in range(50):
            w = np.sqrt(c_hs[k, k] / (mass_matrix[k, k] + np.interp(w, om_all, a_diag[:, k, k])))
        visc[k, k] = args.rao_damping * 2 * w * (mass_matrix[k, k] + np.interp(w, om_all, a_diag[:, k, k]))
    t0 = time.perf_counter()
    motion = rao(ds, dissipation=dof_matrix(visc))
    motion = motion.transpose("omega", "wave_direction", "radiating_dof")
    far = far_field_mean_drift_force(motion, ds)
    drift = np.zeros((len(headings), len(omegas), 6))
    imag = 0.0
    for col, var in ((0, "drift_force_surge"), (1, "drift_force_sway"), (5, "drift_force_yaw")):
        diag = np.diagonal(far[var].values, axis1=1, axis2=2)  # (omega, heading)
        drift[:, :, col] = diag.real.T
        imag = max(imag, np.abs(diag.imag).max() / max(np.abs(diag.real).max(), 1e-300))
    print(f"far-field drift in {time.perf_counter() - t0:.1f} s (diagonal: max |imag|/|real| = {imag:.1e})")

    am = ds.added_mass.transpose("omega", "influenced_dof", "radiating_dof").values
    bd = ds.radiation_damping.transpose("omega", "influenced_dof", "radiating_dof").values
    exc = np.conj(ds.excitation_force.transpose("wave_direction", "omega", "influenced_dof").values)
    coeffs = HydroCoefficients(
        omega=omegas, added_mass=am, damping=bd, added_mass_inf=a_inf, headings=headings,
        excitation_re=exc.real, excitation_im=exc.imag, drift=drift, hydrostatic=c_hs,
        rho=RHO, g=G, volume=volume, reference_point=COG)
    runtime = time.perf_counter() - t_start
    meta = {
        "body": "Wu et al. floating box, Table 1: 45 x 45 m, height 27.5 m, draft 20 m",
        "water_depth_m": DEPTH, "mass_kg": MASS, "inertia_kg_m2": list(INERTIA),
        "center_of_gravity_m": list(COG), "generator": "benchmarks/make_box_hydro.py",
        "capytaine_version": cpt.__version__, "hull_panels": int(mesh.nb_faces),
        "lid_panels": int(lid.nb_faces), "lid_z_m": args.lid_z, "runtime_s": round(runtime, 1),
        "excitation_convention": "e^{+i omega t}; phase relative to incident elevation at x = y = 0",
        "drift": "Capytaine far-field (Maruo) with the freely floating RAO "
                 f"({args.rao_damping:g} of critical viscous roll/pitch damping); heave/roll/pitch set to 0",
        "added_mass_inf": "Capytaine omega = inf on the hull without lid",
    }
    save_hydro(args.out, coeffs, metadata=meta)
    print(f"wrote {args.out} (Capytaine run {runtime:.1f} s)")
    _report(coeffs, np.asarray(mass_matrix))


def _report(coeffs, mass_matrix):
    om = np.asarray(coeffs.omega)
    am = np.asarray(coeffs.added_mass)
    c = np.asarray(coeffs.hydrostatic)
    ainf = np.asarray(coeffs.added_mass_inf)
    print("A∞ diagonal [kg, kg·m²]:", " ".join(f"{x:.4e}" for x in np.diag(ainf)))
    print(f"surge added mass / ρV: {am[0, 0, 0] / (RHO * float(coeffs.volume)):.3f} at ω = {om[0]} rad/s, "
          f"A∞11/ρV = {ainf[0, 0] / (RHO * float(coeffs.volume)):.3f}")
    for k, name in ((2, "heave"), (3, "roll"), (4, "pitch")):
        w = np.sqrt(c[k, k] / (mass_matrix[k, k] + ainf[k, k]))
        for _ in range(50):  # fixed point on A(ω_n)
            a = np.interp(w, om, am[:, k, k])
            w = np.sqrt(c[k, k] / (mass_matrix[k, k] + a))
        print(f"{name}: natural period {2 * np.pi / w:.2f} s (A = {a:.4e}, C = {c[k, k]:.4e})")
    d = np.asarray(coeffs.drift)
    print(f"surge drift at head seas, ω = {om[-1]} rad/s: {d[0, -1, 0]:.4e} N/m² "
          f"(full-reflection limit ½ρgB = {0.5 * RHO * G * WIDTH:.4e})")
    t0 = time.perf_counter()
    ss, rep = fit_radiation(coeffs)
    print(f"radiation fit: {ss.n_states} states in {time.perf_counter() - t0:.1f} s\n{rep}")
    k_hat = np.asarray(ss.transfer(om))
    ogilvie = am - k_hat.imag / om[:, None, None]
    est = np.median(ogilvie[om >= 0.3], axis=0)
    print("A∞ Ogilvie estimate (median over ω ≥ 0.3 rad/s) / Capytaine ω = ∞, diagonal:",
          " ".join(f"{e / a:.3f}" for e, a in zip(np.diag(est), np.diag(ainf))))


if __name__ == "__main__":
    main()
