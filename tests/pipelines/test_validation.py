"""``fretwork validate --quick``: the cylinder-on-plane case against closed forms, in CI."""

import pytest

from pipelines.jobs.validate import run_validation


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    return run_validation(quick=True, out_dir=tmp_path_factory.mktemp("validation"), progress=False)


@pytest.mark.parametrize("case", ["contact_law/tangent", "cylinder_on_plane/hertz",
                                  "cylinder_on_plane/cattaneo_mindlin", "cylinder_on_plane/energy",
                                  "cylinder_on_plane/slip", "cylinder_on_plane/wear_geometry"])
def test_validation_case_passes(records, case):
    selected = [r for r in records if r["case"] == case]
    assert selected, f"no records for {case}"
    for r in selected:
        assert r["passed"], f"{r['quantity']}: {r['value']:.6g} vs {r['reference']:.6g} (tol {r['tolerance']})"
        assert r["rel_error"] <= r["tolerance"]
