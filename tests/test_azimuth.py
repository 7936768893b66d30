"""The trigonometric azimuth interpolant equals direct assembly, and the
spectral bound used for the propagation levels bounds the true spectral radius."""

import numpy as np
import pytest

import gearmodal as gm
from gearmodal.integrate.azimuth import AzimuthAssembler
from gearmodal.integrate.system import PiecewiseLinearSystem

FIELDS = ("M", "C", "K", "G", "K_cent", "f_cent", "B")


@pytest.fixture(scope="module")
def drivetrain():
    return gm.load("studies/models/600kw.toml")


def _close(a, b):
    for f in FIELDS:
        x, y = getattr(a, f), getattr(b, f)
        assert np.abs(x - y).max(initial=0) <= 1e-12 * max(np.abs(y).max(initial=0), 1.0), f
    assert np.abs(a.contacts.W - b.contacts.W).max(initial=0) <= 1e-12
    assert np.abs(a.springs.W - b.springs.W).max(initial=0) <= 1e-12


def test_interpolant_equals_assembly(drivetrain):
    geo = AzimuthAssembler(drivetrain)
    assert geo.exact  # carrier (ratio 1) against ground (ratio 0): a degree-4 polynomial
    for psi in (0.0, 0.3, 2.9, -5.1, 40.0):
        _close(geo.assemble(psi), drivetrain.assemble(azimuth=psi))
    B = geo.load_map(np.array([0.3, 2.9]))
    ref = drivetrain.assemble(azimuth=2.9).B
    # each column to rounding of its own scale (unit loads 1; gravity's, the masses in kg)
    scale = np.maximum(np.abs(ref).max(axis=0), 1.0)
    assert (np.abs(B[1] - ref) <= 1e-13 * scale).all()


def test_too_low_degree_falls_back_to_assembly(drivetrain):
    # the ring (carrier frame) on the housing (ground) makes the coupling rows cos/sin psi:
    # a constant (degree-0) interpolant cannot hold them
    geo = AzimuthAssembler(drivetrain, degree=0)
    assert not geo.exact  # the off-grid check caught it; assemble() then assembles directly


@pytest.mark.parametrize("speed", [0.0, 22.1, 2000.0])
@pytest.mark.parametrize("damping", [0.0, 1e4, 1e7])
def test_spectral_bound(drivetrain, speed, damping):
    asm = drivetrain.assemble(azimuth=0.3)
    asm.C = asm.C + damping * np.eye(asm.n)
    sy = PiecewiseLinearSystem(asm, speed)
    s = asm.contacts.nominal
    A, _ = sy.first_order(s)
    rho = np.abs(np.linalg.eigvals(A)).max()
    bound = sy.spectral_bound(s)
    assert bound >= rho * (1 - 1e-12)
    if damping == 0.0 and speed < 100:
        assert bound <= 1.05 * rho  # tight when lightly damped (the model: ~5 % on meshes)


def test_input_basis_rejects_a_force_outside_it(drivetrain):
    asm = drivetrain.assemble(azimuth=0.3)
    j = asm.load_names.index("rotor.torque")
    sy = PiecewiseLinearSystem(asm, 22.1, inputs=asm.B[:, [j]])
    assert sy.P.shape[1] < asm.n  # the torque column plus the back flanks' offset forces
    F = np.outer([1.0, 2.0], asm.B[:, j])
    assert np.allclose(sy.reduce(F) @ sy.P.T, F)
    k = asm.load_names.index("stage1.carrier.force_x")
    with pytest.raises(gm.ModelError, match="input basis"):
        sy.reduce(np.outer([1.0, 2.0], asm.B[:, k]))


def test_torsional_levels_give_the_same_rows_at_every_azimuth():
    """At the torsional level a planet-bearing or support direction acts on the carrier's
    rotation through its lever arm, which vanishes at particular azimuths (found in review:
    the interpolant could not stack assemblies with 25 and 28 spring rows). A row is kept when
    it acts at the azimuth or at a generic one, so every azimuth has the same rows and the
    interpolant equals direct assembly."""
    m = gm.load("studies/models/600kw.toml",
                overrides={f"stages.{i}.dofs": "torsional" for i in range(3)})
    shapes = {(m.assemble(azimuth=psi).contacts.W.shape, m.assemble(azimuth=psi).springs.W.shape)
              for psi in 2 * np.pi * np.arange(9) / 9}
    assert len(shapes) == 1
    geo = AzimuthAssembler(m)
    assert geo.exact
    for psi in (0.0, 1.1, 3.49):
        _close(geo.assemble(psi), m.assemble(azimuth=psi))


def test_a_model_fitted_before_is_not_fitted_again(monkeypatch):
    """A second AzimuthAssembler of an equal model (the same file loaded again) takes the
    process's kept fit: no assembly is made, and every array at any azimuth is the first fit's
    bit for bit. A changed model is fitted anew, and changing one assembler's arrays leaves
    the kept fit as it was."""
    from gearmodal.integrate import azimuth

    monkeypatch.setattr(azimuth, "FITS_KEPT", 8)  # off by default (the module's note)
    azimuth._FITS.clear()
    first = AzimuthAssembler(gm.load("studies/models/600kw.toml"))
    again = gm.load("studies/models/600kw.toml")
    calls = []
    plain = again.assemble
    again.assemble = lambda **kw: calls.append(kw) or plain(**kw)
    second = AzimuthAssembler(again)
    assert calls == [] and second.model is again and second.exact == first.exact
    for psi in (0.0, 0.7, 2.9):
        a, b = first._values(psi), second._values(psi)
        assert a.keys() == b.keys()
        for key in a:
            np.testing.assert_array_equal(a[key], b[key])
    key = next(k for k in second.coef if k not in second.constant)
    second.coef[key][0][...] = 0.0
    third = AzimuthAssembler(gm.load("studies/models/600kw.toml"))
    np.testing.assert_array_equal(third.coef[key][0], first.coef[key][0])
    stiffer = gm.load("studies/models/600kw.toml")
    bearing = next(iter(stiffer.bearings.values()))
    for k in bearing.stiffness:
        bearing.stiffness[k] *= 2.0
    n = len(azimuth._FITS)
    AzimuthAssembler(stiffer)
    assert len(azimuth._FITS) == n + 1
    azimuth._FITS.clear()  # none left for the tests after it
