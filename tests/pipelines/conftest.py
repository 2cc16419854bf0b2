import pytest
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.fixture
def cylinder_text():
    return (EXAMPLES / "cylinder_on_plane.toml").read_text()


@pytest.fixture
def coarse_cylinder(tmp_path, cylinder_text):
    """The shipped cylinder scene, coarse and short, as a file."""
    text = (cylinder_text.replace("contact_size = 0.05", "contact_size = 0.2")
            .replace("wear_cycles = 20 ", "wear_cycles = 2 ")
            .replace("increments_per_cycle = 40", "increments_per_cycle = 12"))
    path = tmp_path / "coarse.toml"
    path.write_text(text)
    return path
