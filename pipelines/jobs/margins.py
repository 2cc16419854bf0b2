"""Fretting safety margins across the operating range: speed sweep → wing amplitude → margin.

For each engine speed the multibody model gives the wing amplitude (half the peak-to-peak wing
torsion of the scene's counterweight); the margin is the largest amplitude shown to stick / wing
amplitude, where that amplitude is the lower end of the bracket of the limit that
:func:`pipelines.jobs.limit.find_limit` finds on the coupled scene
(:attr:`pipelines.jobs.limit.LimitResult.margin_limit_mm`). The margins are conservative: a
margin of at least 1 means the wing vibrates no more than an amplitude that stuck, and an
amplitude inside the bracket, not shown to stick, has a margin below 1. A margin below 1 is
flagged unsafe (``unsafe_speeds``, red in the plot); an amplitude within the limit's tolerance
of the bracket is "at the limit". Where the whole range stuck, the margins divide its top and are
lower bounds; where nothing stuck, they divide its bottom and are upper bounds, and no speed is
shown safe: those within the bracket (below its bottom) are "at the limit".

Calibration: when the scene states its wing amplitude (``coupling.wing_amplitude``, e.g. a
measured one at the scene's engine speed), every sweep amplitude is scaled by the same factor
(stated amplitude / multibody amplitude at that speed): the excitation of the linear
multibody model is calibrated once, at one speed, as the paper's model was calibrated
against acceleration measurements.

What the sampled speeds do not show is said (:func:`describe_margins`): order/mode crossings
between two sampled speeds, farther than a tenth of the step from both (the amplitude peaks
there, unjudged: the result is then "safe at the sampled speeds"), the unsampled edge of an
unsafe band, which CW is judged (``[coupling] counterweight``) and where another CW's raw
multibody amplitude exceeds it (a ratio of raw amplitudes, no calibration assumed).

The limit is searched at the highest sweep speed: the centrifugal load, which lowers the
clamp force, is then largest, so the one limit is conservative for every speed of the sweep.
"""

from __future__ import annotations

import json
import textwrap
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from pipelines.coupling import CouplingSettings
from pipelines.jobs.limit import LimitResult, find_limit, format_um, plot_limit, write_limit
from reduction.errors import InputError
from reduction.threads import one_blas_thread


@dataclass
class MarginResult:
    """speeds_rpm (n,); wing_amplitude_mm (n,) after calibration; calibration: the factor on the
    multibody amplitudes; limit: the amplitude limit; margin (n,) = limit.margin_limit_mm /
    amplitude, the largest amplitude shown to stick over the wing amplitude.
    warnings: why some amplitudes are not to be trusted (a multibody run, of the sweep or of the
    calibration, that had not settled where its amplitude was measured).
    counterweight: the CW judged (1-based, ``[coupling] counterweight``); crossings_rpm: the
    sweep's order/mode crossings (rpm); multibody_amplitude_mm (n, number of CWs): every CW's
    multibody amplitude, uncalibrated (None: not known)."""

    speeds_rpm: np.ndarray
    wing_amplitude_mm: np.ndarray
    calibration: float
    limit: LimitResult
    margin: np.ndarray
    limit_speed_rpm: float
    warnings: tuple = ()
    counterweight: int = 1
    crossings_rpm: tuple = ()
    multibody_amplitude_mm: np.ndarray | None = None

    @property
    def unsampled_crossings(self) -> list:
        """The crossings (rpm) between two sampled speeds and farther than a tenth of that step
        from both: the amplitude peaks there, and no margin was computed near it."""
        return crossings_between(self.speeds_rpm, self.crossings_rpm)

    @property
    def larger_swings(self) -> list:
        """(CW, speed rpm, ratio) where another CW's multibody amplitude exceeds the judged one's:
        ratios of raw amplitudes, no calibration assumed."""
        return larger_swings(self.speeds_rpm, self.multibody_amplitude_mm, self.counterweight)

    @property
    def failed(self) -> np.ndarray:
        """Speeds whose multibody run failed: no wing amplitude, no margin (bool, (n,))."""
        return np.isnan(self.wing_amplitude_mm)

    @property
    def unsafe(self) -> np.ndarray:
        """Speeds whose margin is below 1: the wing vibrates more than the largest amplitude shown
        to stick (bool, (n,))."""
        return np.isfinite(self.margin) & (self.margin < 1.0)

    @property
    def at_limit(self) -> np.ndarray:
        """Speeds whose wing amplitude lies within the limit's tolerance of its bracket (stuck at
        the lower end, not at the upper): the verdict there is as uncertain as the limit itself
        (bool, (n,)). Where nothing stuck the bracket reaches down to 0; where everything stuck
        there is no limit to be at."""
        if self.limit.limit_mm is None:
            return np.zeros(len(self.margin), dtype=bool)
        low = self.limit.bracket_mm[0] or 0.0
        tolerance = self.limit.tolerance_mm
        return (self.wing_amplitude_mm >= low - tolerance) & (self.wing_amplitude_mm <= self.limit.limit_mm + tolerance)

    def state(self, k: int) -> str:
        """'not judged' (the multibody run failed), 'unsafe', 'at the limit' or 'safe' at the
        k-th speed."""
        if self.failed[k]:
            return "not judged"
        return "unsafe" if self.unsafe[k] else "at the limit" if self.at_limit[k] else "safe"

    def shown_state(self, k: int) -> str:
        """:meth:`state` as it is said: 'not shown safe' for 'at the limit' when nothing of the
        searched range stuck (the margins are then upper bounds: no amplitude was shown to stick)."""
        state = self.state(k)
        return "not shown safe" if state == "at the limit" and self.limit.margin_bound == "upper bound" else state

    def to_json(self) -> dict:
        return {
            "unsafe_speeds": self.speeds_rpm[self.unsafe].tolist(),
            "at_limit_speeds": self.speeds_rpm[self.at_limit].tolist(),
            "failed_speeds": self.speeds_rpm[self.failed].tolist(),
            "speeds_rpm": self.speeds_rpm.tolist(),
            "wing_amplitude_um": (1e3 * self.wing_amplitude_mm).tolist(),
            "calibration_factor": self.calibration,
            "limit_um": None if self.limit.limit_mm is None else 1e3 * self.limit.limit_mm,
            "bracket_um": [None if a is None else 1e3 * a for a in self.limit.bracket_mm],
            "margin_amplitude_um": 1e3 * self.limit.margin_limit_mm,
            "margin_bound": self.limit.margin_bound,
            "limit_speed_rpm": self.limit_speed_rpm,
            "margin": [None if not np.isfinite(m) else float(m) for m in self.margin],
            "smallest_margin": None if not np.isfinite(self.margin).any() else float(np.nanmin(self.margin)),
            "smallest_margin_speed_rpm": None if not np.isfinite(self.margin).any()
            else float(self.speeds_rpm[int(np.nanargmin(self.margin))]),
            "warnings": list(self.warnings),
            "counterweight": self.counterweight,
            "crossings_between_speeds_rpm": self.unsampled_crossings,
            "larger_swings": [{"counterweight": cw, "speed_rpm": speed, "ratio": ratio}
                              for cw, speed, ratio in self.larger_swings],
        }


#: A crossing this close to a sampled speed, as a fraction of the step, counts as sampled.
SAMPLED_FRACTION = 0.1


def crossings_between(speeds_rpm, crossings_rpm) -> list:
    """The crossings (rpm, sorted, unique to 0.1 rpm) inside the sampled range but farther than
    :data:`SAMPLED_FRACTION` of the local step from both neighbouring sampled speeds."""
    speeds = np.unique(np.asarray(speeds_rpm, dtype=float))
    found = set()
    for crossing in crossings_rpm:
        above = int(np.searchsorted(speeds, crossing))
        if above == 0 or above == len(speeds):
            continue
        low, high = speeds[above - 1], speeds[above]
        if min(crossing - low, high - crossing) > SAMPLED_FRACTION * (high - low):
            found.add(round(float(crossing), 1))
    return sorted(found)


def larger_swings(speeds_rpm, amplitude_mm, counterweight: int) -> list:
    """(CW, speed rpm, ratio) for every sampled speed where CW number ``CW`` (1-based) has a larger
    multibody amplitude than ``counterweight``: ratio = its amplitude / the judged one's."""
    if amplitude_mm is None:
        return []
    amplitude = np.asarray(amplitude_mm, dtype=float)
    judged = amplitude[:, counterweight - 1]
    found = []
    for other in range(amplitude.shape[1]):
        if other == counterweight - 1:
            continue
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = amplitude[:, other] / judged
        for k in np.flatnonzero(np.isfinite(ratio) & (ratio > 1.0)):
            found.append((other + 1, float(speeds_rpm[k]), float(ratio[k])))
    return found


def _ratio(value: float) -> str:
    text = f"{value:.2f}"
    return text if text != "1.00" else f"{value:.4f}"


def _finer(speeds_rpm, crossing: float) -> str:
    """A sweep finer around one crossing: from the sampled speed below it to the one above, a
    tenth of that step (rounded to whole rpm, at least 1)."""
    speeds = np.unique(np.asarray(speeds_rpm, dtype=float))
    above = int(np.searchsorted(speeds, crossing))
    low, high = speeds[above - 1], speeds[above]
    return f"{low:g}:{high:g}:{max(1, round((high - low) / 10)):g}"


def crossings_sentence(speeds_rpm, crossings: list) -> str:
    """What the crossings between the sampled speeds mean, or '' when there are none."""
    if not crossings:
        return ""
    listed_ = ", ".join(f"{c:.1f}" for c in crossings)
    return (f"order/mode crossing{'s' if len(crossings) > 1 else ''} at {listed_} rpm "
            f"fall{'' if len(crossings) > 1 else 's'} between the sampled speeds: the margins there are not judged; "
            f"sweep finer around them (e.g. --speeds {_finer(speeds_rpm, crossings[0])})")


def judged_sentence(counterweight: int | None) -> str:
    """Which CW the margins judge, or '' when not known (a file of before it was written)."""
    return "" if counterweight is None else \
        f"the margins judge CW{counterweight} ([coupling] counterweight = {counterweight})"


def swings_sentence(swings: list, counterweight: int) -> str:
    """Where another CW swings more than the judged one, per CW, or '' where none does."""
    parts = []
    for other in sorted({cw for cw, _, _ in swings}):
        at = ", ".join(f"{_ratio(ratio)}× CW{counterweight} at {speed:.0f} rpm"
                       for cw, speed, ratio in swings if cw == other)
        parts.append(f"CW{other} swings {at}: judge it with [coupling] counterweight = {other}")
    return "; ".join(parts)


def band_edges(speeds_rpm, states) -> list:
    """(below, above) rpm pairs of neighbouring sampled speeds, one unsafe and the other safe:
    the edge of the unsafe band lies between them, not sampled."""
    order = np.argsort(speeds_rpm)
    speeds, states = np.asarray(speeds_rpm, dtype=float)[order], [states[k] for k in order]
    return [(float(speeds[k]), float(speeds[k + 1])) for k in range(len(speeds) - 1)
            if {states[k], states[k + 1]} == {"unsafe", "safe"}]


def edges_sentence(edges: list) -> str:
    """'(the unsafe band's edge lies between 600 and 650 rpm, not sampled)' or ''."""
    if not edges:
        return ""
    between = " and ".join(f"between {low:.0f} and {high:.0f} rpm" for low, high in edges)
    return (f"(the unsafe band's edge lies {between}, not sampled)" if len(edges) == 1
            else f"(the unsafe bands' edges lie {between}, not sampled)")


def _rpm(speeds) -> str:
    return ", ".join(f"{v:.0f}" for v in speeds) + " rpm"


def _um(result: MarginResult, amplitude_mm: float) -> str:
    return format_um(amplitude_mm, result.limit.tolerance_mm)


def margin_basis(result: MarginResult) -> str:
    """What the margins divide, in words: the amplitude (µm), why that one, and the search speed."""
    limit, searched = result.limit, f"searched at {result.limit_speed_rpm:.0f} rpm"
    if limit.margin_bound == "lower bound":
        return (f"stuck over the whole searched range, up to {_um(result, limit.margin_limit_mm)} µm ({searched}): "
                "the margins are lower bounds")
    if limit.margin_bound == "upper bound":
        return (f"not stuck even at {_um(result, limit.margin_limit_mm)} µm, the bottom of the searched range "
                f"({searched}): the margins are upper bounds")
    return f"sticks up to {_um(result, limit.bracket_mm[0])} µm, not at {_um(result, limit.limit_mm)} µm ({searched})"


def describe_margins(result: MarginResult) -> str:
    """One line: which CW is judged; the unsafe speeds (margin below 1, with the unsampled edges
    of their band) and those at the limit, or that all are safe — "at the sampled speeds" where
    order/mode crossings fall between them, which are listed; margins that are bounds are said to
    be; other CWs that swing more than the judged one."""
    states = [result.state(k) for k in range(len(result.speeds_rpm))]
    unsafe, at_limit = result.speeds_rpm[result.unsafe], result.speeds_rpm[result.at_limit & ~result.unsafe]
    failed = result.speeds_rpm[result.failed]
    safe = np.array([state == "safe" for state in states], dtype=bool)
    bound = result.limit.margin_bound
    stuck = f"{_um(result, result.limit.margin_limit_mm)} µm"
    crossings = result.unsampled_crossings
    parts = []
    if failed.size:
        parts.append(f"NOT JUDGED at {_rpm(failed)}: the multibody run failed there (the sweep's failures), "
                     "so there is no wing amplitude to judge")
    if unsafe.size:
        exceeded = {"stuck": f"{stuck}, the largest amplitude shown to stick",
                    "lower bound": f"{stuck}, the top of the searched range, all of which stuck",
                    "upper bound": f"{stuck}, the bottom of the searched range, which did not stick"}[bound]
        edges = edges_sentence(band_edges(result.speeds_rpm, states))
        parts.append(f"UNSAFE at {_rpm(unsafe)}: the wing vibration exceeds {exceeded} (margin below 1)"
                     + (f" {edges}" if edges else ""))
    if at_limit.size:
        parts.append(f"not shown safe at {_rpm(at_limit)}: nothing in the searched range stuck" if bound == "upper bound"
                     else f"at the limit at {_rpm(at_limit)} (within the limit's tolerance of its bracket)")
    if not parts:
        said = f"safe at {'the sampled' if crossings else 'every'} speed{'s' if crossings else ''} (every margin at least 1)"
    else:
        said = "; ".join(parts) + (f"; safe at the {'other sampled speeds' if crossings else 'others'}" if safe.any() else "")
    if bound != "stuck":
        said += f"; the margins are {bound}s ({'the whole range stuck' if bound == 'lower bound' else 'nothing stuck'})"
    for sentence in (crossings_sentence(result.speeds_rpm, crossings), judged_sentence(result.counterweight),
                     swings_sentence(result.larger_swings, result.counterweight)):
        if sentence:
            said += f"; {sentence}"
    if result.warnings:
        said += f"; WARNING, {len(result.warnings)} amplitude(s) not to be trusted: " + " | ".join(result.warnings)
    return said


def calibration_factor(scene, cache) -> tuple[float, str | None]:
    """(stated wing amplitude / multibody wing amplitude at the scene's speed, or 1 if none is
    stated; why that multibody amplitude is not to be trusted, or None)."""
    from pipelines.coupling import multibody_loading

    stated = scene.data["coupling"].get("wing_amplitude")
    if stated is None:
        return 1.0, None
    loading = multibody_loading(scene, cache)
    if loading.wing_amplitude <= 0:
        raise InputError("the multibody run shows no wing vibration at the scene's speed: cannot calibrate")
    return float(stated) / loading.wing_amplitude, loading.unsettled


@one_blas_thread
def margin_sweep(scene_path, speeds, *, amplitude_range_mm, tolerance_mm, cache_dir=None, sweep_path=None,
                 out_dir=None, scheduler=None, workers=None, progress=True, overrides=None):
    """Speed sweep, amplitude limit and margins (module doc); returns (MarginResult, SweepResult).
    out_dir: the folder of the limit's runs, where its limit.json and limit.png go too."""
    from pipelines.jobs.sweep import speed_sweep
    from pipelines import scene as scenes
    from pipelines.coupling import multibody_params
    from pipelines.stages import StageCache

    scene = scenes.load(scene_path, overrides or None)
    if "coupling" not in scene.data:
        raise InputError(f"{scene_path}: --margins needs a coupled scene (a [coupling] table) for the limit")
    cache = StageCache(cache_dir)
    speeds = np.asarray(speeds, dtype=float)
    sweep = speed_sweep(multibody_params(scene), speeds, path=sweep_path, progress=progress,
                        scheduler=scheduler, workers=workers)
    limit_overrides = dict(overrides or {}, **{"mbs.speed_rpm": float(speeds.max())})
    limit = find_limit(scene_path, *amplitude_range_mm, tolerance_mm=tolerance_mm, overrides=limit_overrides,
                       cache_dir=cache_dir, out_dir=out_dir, scheduler=scheduler, workers=workers, progress=progress)
    if out_dir is not None:  # beside the limit's runs, as `fretwork limit` and the demo write them
        write_limit(limit, Path(out_dir) / "limit.json")
        plot_limit(limit, Path(out_dir) / "limit.png", scene.name)
    result = margins_of(scene, sweep, limit, cache)
    if sweep_path is not None:
        write_margins(sweep_path, result)
    return result, sweep


def margins_of(scene, sweep, limit: LimitResult, cache) -> MarginResult:
    """Calibrated wing amplitude of the scene's CW per sweep speed and margin = the largest
    amplitude shown to stick / amplitude (:attr:`LimitResult.margin_limit_mm`, the limit searched
    at the highest sweep speed)."""
    counterweight = CouplingSettings.of(scene).counterweight - 1
    factor, calibration_warning = calibration_factor(scene, cache)
    amplitude = factor * sweep.wing_amplitude[:, counterweight]
    # no vibration: an infinite margin; a failed multibody run (NaN amplitude): no margin at all
    margin = np.divide(limit.margin_limit_mm, amplitude, out=np.full_like(amplitude, np.inf), where=amplitude > 0)
    margin[np.isnan(amplitude)] = np.nan
    speeds = np.asarray(sweep.speeds_rpm, dtype=float)
    warnings = [f"calibration: {calibration_warning}"] if calibration_warning else []
    warnings += list((sweep.unsettled or {}).values())
    return MarginResult(speeds, amplitude, factor, limit, margin, float(speeds.max()), tuple(warnings),
                        counterweight=counterweight + 1,
                        crossings_rpm=tuple(float(c["speed_rpm"]) for c in getattr(sweep, "crossings", ())),
                        multibody_amplitude_mm=np.asarray(sweep.wing_amplitude, dtype=float))


def write_margins(path, result: MarginResult) -> None:
    """Group /margins of the sweep file (units as attributes)."""
    with h5py.File(path, "a") as handle:
        if "margins" in handle:
            del handle["margins"]
        group = handle.create_group("margins")
        group.attrs["description"] = ("fretting safety margin = margin_amplitude_mm (the largest amplitude shown to "
                                      "stick) / wing amplitude per engine speed")
        group.attrs["calibration_factor"] = result.calibration
        group.attrs["limit_speed_rpm"] = result.limit_speed_rpm
        for name, data, units in (("speed_rpm", result.speeds_rpm, "rpm"),
                                  ("wing_amplitude", result.wing_amplitude_mm, "mm"),
                                  ("margin", result.margin, "1"),
                                  ("unsafe", result.unsafe, "1")):
            group.create_dataset(name, data=data).attrs["units"] = units
        group["unsafe"].attrs["description"] = "1 where the margin is below 1, else 0"
        group.attrs["limit_mm"] = np.nan if result.limit.limit_mm is None else result.limit.limit_mm
        group.attrs["margin_amplitude_mm"] = result.limit.margin_limit_mm
        group.attrs["margin_bound"] = result.limit.margin_bound
        group.attrs["counterweight"] = result.counterweight
        group.attrs["crossings_between_speeds_rpm"] = np.asarray(result.unsampled_crossings, dtype=float)
        group.attrs["larger_swings_json"] = json.dumps(result.to_json()["larger_swings"])


def plot_margins(result: MarginResult, path: Path, title: str) -> Path:
    """Wing amplitude and limit versus speed (top), margin versus speed (bottom)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    top.plot(result.speeds_rpm, 1e3 * result.wing_amplitude_mm, "-", color="0.6", label="wing amplitude")
    limit = result.limit
    top.axhline(1e3 * limit.margin_limit_mm, color="tab:red", linestyle="--" if limit.margin_bound == "stuck" else ":",
                label=textwrap.fill(margin_basis(result), 60))
    if limit.margin_bound == "stuck":  # not shown to stick inside the bracket
        top.axhspan(1e3 * limit.bracket_mm[0], 1e3 * limit.limit_mm, color="tab:red", alpha=0.12, lw=0)
    top.set_ylabel("wing amplitude (µm)")
    low, high = top.get_ylim()
    top.set_ylim(low, high + 0.25 * (high - low))  # room for the legend above the limit line
    top.legend(loc="upper right", fontsize=8)
    top.grid(True, alpha=0.3)
    bottom.plot(result.speeds_rpm, result.margin, "-", color="0.6", zorder=1)
    colours = {"safe": "tab:green", "at the limit": "tab:orange", "unsafe": "tab:red"}
    states = np.array([result.state(k) for k in range(len(result.speeds_rpm))])
    for state, colour in colours.items():
        chosen = states == state
        if chosen.any():
            label = {"unsafe": "unsafe: margin < 1", "at the limit": "not shown safe (upper bound)"
                     if limit.margin_bound == "upper bound" else "at the limit"}.get(state, state)
            bottom.scatter(result.speeds_rpm[chosen], result.margin[chosen], color=colour, label=label, zorder=2)
            top.scatter(result.speeds_rpm[chosen], 1e3 * result.wing_amplitude_mm[chosen], color=colour, zorder=3)
    for k, speed in enumerate(result.speeds_rpm[result.failed]):  # no amplitude to draw: the speed is marked
        for axis in (top, bottom):
            axis.axvline(speed, color="0.5", linestyle=":", linewidth=1.2,
                         label="multibody run failed: not judged" if k == 0 and axis is bottom else None)
    bottom.axhline(1.0, color="tab:red", linewidth=1)
    bottom.legend(loc="best")
    bottom.set_ylabel("safety margin\n(stuck amplitude / wing amplitude)")
    bottom.set_xlabel("engine speed (rpm)")
    bottom.grid(True, alpha=0.3)
    top.set_title(title)
    figure.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path
