"""The shipped scenes, installed as package data of ``pipelines.examples``.

``fretwork demo`` and ``fretwork validate`` read them from the installed package, so they work
from any directory and from a non-editable install. See the README for what each scene shows.
"""

from pathlib import Path

FOLDER = Path(__file__).resolve().parent


def scene_path(name: str) -> Path:
    """Path of the shipped scene ``name`` (file name without ``.toml``)."""
    return FOLDER / f"{name}.toml"
