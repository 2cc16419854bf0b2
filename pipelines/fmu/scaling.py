"""The loads a coupled run used: its multibody histories scaled to the stated wing amplitude.

A coupled ``fretwork run`` keeps in ``/histories`` the multibody histories as the multibody model
gave them, and in the group's ``vibration_scale`` attribute the factor its contact load cycle
applied to their vibrating parts (:func:`mbs.loading.cycle_loading`: the stated wing amplitude
over the multibody one). An FMU made from such a file plays the histories as the run used them,
each scaled about its mean as the load cycle scales it:

* ``wing_period`` cycle: every history is its mean plus its harmonic at the dominant wing
  frequency (least squares, :func:`mbs.loading.harmonic_fit`), the harmonic scaled; the other
  frequencies of the multibody histories are not in the run's loads, so not in the FMU either;
* ``revolution`` cycle: every history is its mean over the last engine revolution plus the scaled
  difference from it.

The played wing torsion then swings by the stated wing amplitude. ``fretwork mbs``'s ``run.h5``
has no ``vibration_scale``: its histories are played as they are. Units: mm, s, Hz.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from mbs.histories import wing_amplitude
from mbs.loading import harmonic_fit
from mbs.spectra import peak_frequency
from pipelines import scene as scenes
from pipelines.coupling import CouplingSettings
from reduction.errors import InputError


@dataclass(frozen=True)
class LoadScaling:
    """How a coupled run's load cycle used its multibody histories.

    scale: factor on the vibrating part of every history; cycle: "wing_period" or "revolution";
    frequency_hz: of the harmonic kept (wing_period) or of the engine revolution (revolution);
    scaled_amplitude: the multibody amplitude the scale applies to, mm: the amplitude of the wing
    torsion's harmonic at frequency_hz (wing_period), its half peak-to-peak (revolution);
    wing_amplitude: the run's stated wing amplitude, mm (scale × scaled_amplitude);
    multibody_wing_amplitude: half peak-to-peak of the multibody wing torsion, mm (the project's
    wing amplitude); counterweight: which CW (1 = first); window: (n,) bool, the samples the means
    are taken over (all for wing_period, the last revolution for revolution).
    """

    scale: float
    cycle: str
    frequency_hz: float
    scaled_amplitude: float
    wing_amplitude: float
    multibody_wing_amplitude: float
    counterweight: int
    window: np.ndarray

    def apply(self, time: np.ndarray, values: np.ndarray) -> np.ndarray:
        """``values`` (n, k) at ``time`` (n,) s as the run's load cycle used them."""
        if self.cycle == "wing_period":
            mean, cosine, sine = harmonic_fit(time, values, self.frequency_hz)
            phase = 2.0 * np.pi * self.frequency_hz * (time - time[0])
            return mean + self.scale * (np.outer(np.cos(phase), cosine) + np.outer(np.sin(phase), sine))
        mean = values[self.window].mean(axis=0)
        return mean + self.scale * (values - mean)

    def describe(self) -> str:
        """One sentence for the FMU's description: the scale times the amplitude it applies to is
        the stated wing amplitude, and the multibody wing amplitude is named apart from it."""
        multibody = "the multibody wing amplitude (half the peak-to-peak of the wing torsion)"
        stated = f"the stated wing amplitude {self.wing_amplitude:.6g} mm of cw{self.counterweight}"
        if self.cycle == "wing_period":
            return (f"as the coupled run used them ({self.cycle} load cycle): each history its mean plus its "
                    f"harmonic at {self.frequency_hz:.6g} Hz, the harmonic scaled by {self.scale:.6g}: "
                    f"{self.scale:.6g} × {self.scaled_amplitude:.6g} mm, the amplitude of the wing torsion's "
                    f"harmonic in the multibody run, is {stated}; {multibody} is "
                    f"{self.multibody_wing_amplitude:.6g} mm")
        return (f"as the coupled run used them ({self.cycle} load cycle): each history about its mean over the "
                f"last revolution, its difference from that mean scaled by {self.scale:.6g}: "
                f"{self.scale:.6g} × {self.scaled_amplitude:.6g} mm, {multibody}, is {stated}")


def load_scaling(results: h5py.File, time: np.ndarray, results_path: Path) -> LoadScaling | None:
    """The scaling of a coupled run's ``/histories`` (``time`` its samples, s); None when the file
    states none (``fretwork mbs``'s ``run.h5``)."""
    histories = results["histories"]
    if "vibration_scale" not in histories.attrs:
        return None
    scale = float(histories.attrs["vibration_scale"])
    counterweight = int(histories.attrs.get("counterweight", 1))
    name = f"cw{counterweight}_wing_torsion"
    if name not in histories:
        raise InputError(f"results file {results_path}: /histories is scaled (vibration_scale {scale:g}) but holds "
                         f"no {name}, the wing torsion its scale refers to")
    torsion = np.asarray(histories[name][()], dtype=np.float64)
    cycle = _load_cycle(results, results_path)
    if cycle == "wing_period":
        frequency = peak_frequency(time, torsion)
        _, cosine, sine = harmonic_fit(time, torsion, frequency)
        reference = float(np.hypot(cosine, sine))
        window = np.ones(time.size, dtype=bool)
    else:
        revolution = 60.0 / float(histories.attrs["speed_rpm"])
        frequency = 1.0 / revolution
        reference = float(wing_amplitude(torsion))
        window = time >= time[-1] - revolution
    return LoadScaling(scale, cycle, frequency, reference, scale * reference, float(wing_amplitude(torsion)),
                       counterweight, window)


def _load_cycle(results: h5py.File, results_path: Path) -> str:
    """The run's ``[coupling] cycle``: the ``load_cycle`` attribute of /histories, or, in files
    that do not record it, the run's scene as the file records it (``scene_toml``: the resolved
    scene; in older files the scene file's own text, then the base scene it extends)."""
    recorded = results["histories"].attrs.get("load_cycle")
    if recorded is not None:
        return recorded.decode() if isinstance(recorded, bytes) else str(recorded)
    text = str(results.attrs.get("scene_toml", ""))
    if not text:
        raise InputError(f"results file {results_path} records neither its load cycle nor its scene: the scaling "
                         "of its histories cannot be reproduced")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise InputError(f"results file {results_path}: its scene (scene_toml) is not valid TOML ({error}), so the "
                         "load cycle that scaled its histories is unknown") from None
    cycle = data.get("coupling", {}).get("cycle")
    base = data.get("scene", {}).get("base")
    if cycle is None and base is not None:
        if not Path(base).is_absolute():
            raise InputError(f"results file {results_path} does not record its load cycle, and its scene leaves it "
                             f"to the base scene {base!r}, a path relative to the scene's folder, which the file "
                             "does not record: run the scene again to record the cycle with the histories")
        cycle = scenes.tables(base).get("coupling", {}).get("cycle")
    return cycle or CouplingSettings.cycle
