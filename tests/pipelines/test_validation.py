"""``fretwork validate --quick``: the cylinder-on-plane case against closed forms, in CI.

The tolerances are pinned here, not read from ``pipelines/validate.py``: loosening one there
must fail this test and show in review. The mortar patch test and the finite-sliding check
are also run as they must not pass: node-to-segment pairing on the same meshes, and the
pairing held fixed (small sliding) in the same gross slip. The finite-sliding scars are also
checked on contact elements half the shipped size: their tolerance is one element, whatever it is.
"""

import pytest

from pipelines.jobs.validate import SCENE, check_finite_sliding, check_mortar_patch, run_validation
from reduction.threads import single_threaded_blas


def one_element(size):
    """A width's tolerance: one contact element of ``size`` mm, relative to the reference width."""
    return lambda record: size / record["reference"]


#: (case, start of the quantity's name) → relative tolerance of the check, or the rule that
#: gives it from the record.
PINNED = {
    ("contact_law/tangent", "FD tangent error, stick, normal entries"): 1e-6,
    ("contact_law/tangent", "FD tangent error, stick, friction entries"): 1e-6,
    ("contact_law/tangent", "FD tangent error, stick, coupling entries"): 1e-6,
    ("contact_law/tangent", "FD tangent error, slip, normal entries"): 1e-6,
    ("contact_law/tangent", "FD tangent error, slip, friction entries"): 1e-6,
    ("contact_law/tangent", "FD tangent error, slip, coupling entries"): 1e-6,
    ("contact_law/tangent", "FD tangent error, slip with pressure change, normal entries"): 1e-6,
    ("contact_law/tangent", "FD tangent error, slip with pressure change, friction entries"): 1e-6,
    ("contact_law/tangent", "FD tangent error, slip with pressure change, coupling entries"): 1e-6,
    ("cylinder_on_plane/hertz", "peak pressure p0"): 0.02,
    ("cylinder_on_plane/hertz", "half-width a"): 0.02,
    ("cylinder_on_plane/cattaneo_mindlin", "stick half-width c"): 0.05,
    ("cylinder_on_plane/energy", "worn area vs w x global dissipation [mm^2 per mm of length]"): 0.01,
    ("cylinder_on_plane/energy", "dissipation per gross-slip cycle"): 0.05,
    ("cylinder_on_plane/slip", "slip amplitude at the centre"): 0.03,
    ("cylinder_on_plane/wear_geometry", "max wear depth"): 0.05,
    ("cylinder_on_plane/wear_geometry", "scar width"): 0.05,
    ("flat_blocks/mortar_patch", "pressure, worst point, 2D 0.4 on 0.3 mm"): 1e-5,
    ("flat_blocks/mortar_patch", "pressure, worst point, 2D 0.3 on 0.4 mm"): 1e-5,
    ("flat_blocks/mortar_patch", "pressure, worst point, 3D 7x7 on 10x10"): 1e-5,
    ("flat_blocks/mortar_patch", "pressure, worst point, 3D 10x10 on 7x7"): 1e-5,
    ("cylinder_on_plane/finite_sliding", "cylinder scar width at 10% depth vs Hertz 2a"): one_element(0.1),
    ("cylinder_on_plane/finite_sliding", "flat scar width at 10% depth vs the cylinder's swept"): one_element(0.1),
    ("cylinder_on_plane/finite_sliding", "worn area vs w x global dissipation [mm^2 per mm of length]"): 0.005,
}


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    return run_validation(quick=True, out_dir=tmp_path_factory.mktemp("validation"), progress=False)


def _pinned(record, pinned=PINNED) -> float:
    matches = [(len(start), tolerance) for (case, start), tolerance in pinned.items()
               if record["case"] == case and record["quantity"].startswith(start)]
    assert matches, f"{record['case']}: '{record['quantity']}' has no pinned tolerance in this test"
    tolerance = max(matches, key=lambda match: match[0])[1]  # the longest name that matches
    return tolerance(record) if callable(tolerance) else tolerance


def test_every_check_has_its_pinned_tolerance(records):
    for r in records:
        assert r["tolerance"] == _pinned(r), f"{r['quantity']}: tolerance changed in pipelines/validate.py"
    checked = {(case, start) for r in records for (case, start) in PINNED
               if r["case"] == case and r["quantity"].startswith(start)}
    assert checked == set(PINNED), f"checks no longer run: {set(PINNED) - checked}"


@pytest.mark.parametrize("case", sorted({case for case, _ in PINNED}))
def test_validation_case_passes(records, case):
    selected = [r for r in records if r["case"] == case]
    assert selected, f"no records for {case}"
    for r in selected:
        tolerance = _pinned(r)
        assert r["rel_error"] <= tolerance, \
            f"{r['quantity']}: {r['value']:.6g} vs {r['reference']:.6g} (tol {tolerance})"
        assert r["passed"], f"{r['quantity']}: failed its own check (regime or tolerance)"


def test_node_to_segment_pairing_fails_the_patch_test():
    """The same non-matching faces paired node-to-segment: pressures scatter by 8-47 %, four
    orders of magnitude beyond the tolerance the mortar pairing meets."""
    records = check_mortar_patch(SCENE, {}, pairing="node_to_segment")
    assert len(records) == 4
    for r in records:
        assert not r["passed"] and r["rel_error"] > 0.05, r


@pytest.mark.parametrize("element", [0.1, 0.05])
def test_finite_sliding_scars_hold_on_either_mesh(tmp_path, element):
    """The scars at the shipped 0.1 mm elements and at 0.05 mm, each within one element of its
    reference (measured: 0.006-0.019 mm on both). The flat's tail below 0.1 % of its depth,
    which the check once measured to, ended 0.09 mm short on the finer mesh."""
    pinned = {key: one_element(element) if callable(tolerance) else tolerance for key, tolerance in PINNED.items()}
    with single_threaded_blas():
        records = check_finite_sliding(SCENE, {}, cycles=2, increments=80, out_dir=tmp_path, element=element)
    assert len(records) == 3
    for r in records:
        assert r["tolerance"] == pytest.approx(_pinned(r, pinned), rel=1e-12), r
        assert r["passed"], f"{r['quantity']}: {r['value']:.4f} vs {r['reference']:.4f} (tol {r['tolerance']:.4f})"


@pytest.mark.parametrize("element", [0.1, 0.05])
def test_small_sliding_fails_the_finite_sliding_check(tmp_path, element):
    """With the pairing fixed the flat's wear stays where the cylinder's points started: its
    scar is the cylinder's, short of the cylinder's swept by ±δ by 0.52 mm at 10 % depth (five
    elements of 0.1 mm, ten of 0.05 mm)."""
    with single_threaded_blas():
        records = check_finite_sliding(SCENE, {}, cycles=1, increments=80, out_dir=tmp_path, mode="small",
                                       element=element)
    flat = next(r for r in records if r["quantity"].startswith("flat scar width"))
    assert not flat["passed"] and flat["reference"] - flat["value"] > 0.4, flat
