"""The planar planetary stage assembled from the symbolic kernels equals Lin & Parker (1999).

Lin & Parker's equations in the frame rotating with the carrier at Omega are

    M q'' + Omega G q' + (K_b + K_m - Omega^2 K_Omega) q = T

with q = [x_c y_c u_c, x_r y_r u_r, x_s y_s u_s, zeta_1 eta_1 u_1, ...]. They are written out
here independently of gearmodal: masses, gyroscopic blocks, support stiffness, and the mesh and
planet-bearing stiffness as outer products of Lin & Parker's deflections (their eqs. for
delta_sn, delta_rn and the planet bearing deflections, DESIGN 2.6). The parameter set is Lin &
Parker's Table 1 example system.
"""

import math

import numpy as np
import pytest

import gearmodal as gm

LP = {
    "mass": {"carrier": 5.43, "ring": 2.35, "sun": 0.4, "planet": 0.66},
    "inertia_over_r2": {"carrier": 6.29, "ring": 3.0, "sun": 0.39, "planet": 0.61},
    "bearing": {"carrier": 1e8, "ring": 1e8, "sun": 1e8, "planet": 1e8},
    "torsional": {"carrier": 0.0, "ring": 1e9, "sun": 0.0},
    "mesh": {"sun_planet": 5e8, "ring_planet": 5e8},
}


def lin_parker_matrices(n, psi, alpha_s, alpha_r, p=LP):
    m, i2, kb, kt, km = (p[k] for k in ("mass", "inertia_over_r2", "bearing", "torsional",
                                        "mesh"))
    N = 3 * (3 + n)
    M = np.diag([m["carrier"], m["carrier"], i2["carrier"], m["ring"], m["ring"], i2["ring"],
                 m["sun"], m["sun"], i2["sun"]] + [m["planet"], m["planet"], i2["planet"]] * n)
    G = np.zeros((N, N))
    K_omega = np.zeros((N, N))
    for j in range(3 + n):
        mj = M[3 * j, 3 * j]
        G[3 * j, 3 * j + 1], G[3 * j + 1, 3 * j] = -2 * mj, 2 * mj
        K_omega[3 * j, 3 * j] = K_omega[3 * j + 1, 3 * j + 1] = mj
    K_b = np.diag([kb["carrier"], kb["carrier"], kt["carrier"], kb["ring"], kb["ring"],
                   kt["ring"], kb["sun"], kb["sun"], kt["sun"]] + [0.0] * (3 * n))
    K_m = np.zeros((N, N))
    C, R, S = 0, 3, 6
    for k in range(n):
        P = 9 + 3 * k
        ps, pr = psi[k] - alpha_s, psi[k] + alpha_r
        d_sn = np.zeros(N)
        d_sn[S:S + 3] = [-math.sin(ps), math.cos(ps), 1.0]
        d_sn[P:P + 3] = [-math.sin(alpha_s), -math.cos(alpha_s), 1.0]
        d_rn = np.zeros(N)
        d_rn[R:R + 3] = [-math.sin(pr), math.cos(pr), 1.0]
        d_rn[P:P + 3] = [math.sin(alpha_r), -math.cos(alpha_r), -1.0]
        d_pr = np.zeros(N)
        d_pr[C:C + 2] = [math.cos(psi[k]), math.sin(psi[k])]
        d_pr[P] = -1.0
        d_pt = np.zeros(N)
        d_pt[C:C + 3] = [-math.sin(psi[k]), math.cos(psi[k]), 1.0]
        d_pt[P + 1] = -1.0
        K_m += km["sun_planet"] * np.outer(d_sn, d_sn) + km["ring_planet"] * np.outer(d_rn, d_rn)
        K_m += kb["planet"] * (np.outer(d_pr, d_pr) + np.outer(d_pt, d_pt))
    return M, G, K_b + K_m, K_omega


CASES = [
    (3, None, 24.6, 24.6),
    (4, None, 24.6, 24.6),
    (5, None, 20.0, 22.5),
    (4, [0.0, 1.4, 3.3, 4.6], 24.6, 24.6),  # unequal spacing
]


@pytest.mark.parametrize("n, angles, a_s_deg, a_r_deg", CASES)
def test_planar_stage_equals_lin_parker(n, angles, a_s_deg, a_r_deg):
    a_s, a_r = math.radians(a_s_deg), math.radians(a_r_deg)
    model = gm.lin_parker_stage(n, LP["mass"], LP["inertia_over_r2"], LP["bearing"],
                                LP["torsional"], LP["mesh"],
                                {"sun_planet": a_s, "ring_planet": a_r}, planet_angles=angles)
    psi = angles or [2 * math.pi * k / n for k in range(n)]
    M, G, K, K_omega = lin_parker_matrices(n, psi, a_s, a_r)
    asm = model.assemble()
    names = (["carrier.x", "carrier.y", "carrier.u", "ring.x", "ring.y", "ring.u",
              "sun.x", "sun.y", "sun.u"]
             + [f"planet{k}.{c}" for k in range(1, n + 1) for c in ("zeta", "eta", "u")])
    assert asm.dof_names == names
    # Entries are sums of products of O(1e9) stiffness with sines; 1e-9 relative to the
    # largest entry is a few hundred ulp of accumulated rounding.
    scale = np.abs(K).max()
    np.testing.assert_allclose(asm.M, M, rtol=0, atol=1e-12 * np.abs(M).max())
    np.testing.assert_allclose(asm.G, G, rtol=0, atol=1e-12 * np.abs(G).max())
    # Lin & Parker's centripetal-only form (geometric_stiffness=False)
    np.testing.assert_allclose(asm.speed_stiffness(False), -K_omega, rtol=0,
                               atol=1e-12 * np.abs(M).max())
    np.testing.assert_allclose(asm.stiffness(), K, rtol=0, atol=1e-12 * scale)
    # at speed: K_b + K_m - Omega^2 K_Omega and Omega G
    om = 37.0
    np.testing.assert_allclose(asm.stiffness(speed=om) - om**2 * asm.K_geom,
                               K - om**2 * K_omega, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(asm.damping(speed=om), om * G, rtol=0,
                               atol=1e-12 * om * np.abs(G).max())


def test_back_flank_is_mirror_of_front():
    """Back flank deflection: the radial terms of the front flank, rotational and tangential
    terms with flipped sign (DESIGN 2.6); its offset is the backlash."""
    n, a = 3, math.radians(24.6)
    model = gm.lin_parker_stage(n, LP["mass"], LP["inertia_over_r2"], LP["bearing"],
                                LP["torsional"], LP["mesh"], a, backlash=2e-4)
    asm = model.assemble()
    c = asm.contacts
    names = asm.dof_names
    for k in range(1, n + 1):
        for mesh in (f"sun_planet{k}", f"ring_planet{k}"):
            front = c.W[c.index(mesh, "front")]
            back = c.W[c.index(mesh, "back")]
            zeta = names.index(f"planet{k}.zeta")
            eta = names.index(f"planet{k}.eta")
            u = names.index(f"planet{k}.u")
            assert back[zeta] == pytest.approx(front[zeta], abs=1e-14)
            assert back[eta] == pytest.approx(-front[eta], abs=1e-14)
            assert back[u] == pytest.approx(-front[u], abs=1e-14)
    assert np.all(c.offset[np.array(c.contact) == "back"] == 2e-4)
    assert np.all(c.offset[np.array(c.contact) == "front"] == 0.0)
