"""The file-format reference page is generated from the schema and kept current (issue 20)."""

from pathlib import Path

from gearmodal import reference


def test_the_file_format_page_is_current():
    page = Path(reference.PAGE)
    assert page.read_text(encoding="utf-8") == reference.markdown(), (
        "docs/file-format.md is not current: run python -m gearmodal.reference")


def test_the_page_lists_every_key_the_loader_accepts():
    text = reference.markdown()
    for key in ("pressure_angle_deg", "planet_angles_deg", "clearance_shape", "coupling_stiffness",
                "inertia_over_r2", "alternation", "pinned_to", "axes_frame", "speed_ratio",
                "rebase_angle", "turbulence_intensity", "twist_deg", "frequency_hz", "t_start"):
        assert f"`{key}" in text, key
