"""``fretwork study accuracy SCENE``: the command line of the accuracy study."""

from __future__ import annotations

import sys
import tomllib
from pathlib import Path

from pipelines.cli import json_text
from pipelines.parallel import add_cluster_arguments
from reduction.errors import InputError


def _parse_value(text: str, where: str):
    try:
        return tomllib.loads(f"value = {text}")["value"]
    except tomllib.TOMLDecodeError:
        raise InputError(f"{where}: '{text}' is not a TOML value (number, true/false, \"text\")") from None


def _parse_pairs(items: list[str], option: str) -> dict:
    pairs = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key or not value:
            raise InputError(f"{option} '{item}' must read NAME=VALUE")
        pairs[key.strip()] = value.strip()
    return pairs


def set_overrides(items: list[str]) -> dict:
    """Scene overrides from ``--set KEY=VALUE`` options: {dotted key: TOML value}; a KEY that
    no scene has is said as the option's, with "did you mean" (not as the scene file's)."""
    from pipelines.scene.schema import unknown_key

    pairs = _parse_pairs(items, "--set")
    for key in pairs:
        problem = unknown_key(key)
        if problem:
            raise InputError(f"--set {key}: {problem}")
    return {key: _parse_value(value, f"--set {key}") for key, value in pairs.items()}


def cmd_accuracy(args) -> int:
    """``fretwork study accuracy``: run the study, print the table (or JSON), write plot and JSON."""
    from pipelines.studies.accuracy import accuracy_study  # the study's modules load only when it runs
    from pipelines.studies.accuracy_report import plot_pareto, table_lines

    overrides = set_overrides(args.set)
    sweeps = {key: [_parse_value(v, f"--knob {key}") for v in value.split(",")]
              for key, value in _parse_pairs(args.knob, "--knob").items()}
    for key, values in sweeps.items():
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0 for v in values):
            raise InputError(f"--knob {key}: values must be positive numbers, got {values}")

    def progress(record):
        state = "did not converge" if record["failure"] else f"worst error {100 * record['worst_error']:.2f} %"
        print(f"  {record['label']}: CPU {record['cpu_time_s']:.1f} s, wall {record['wall_time_s']:.1f} s, {state}",
              file=sys.stderr, flush=True)

    study = accuracy_study(args.scene, quick=args.quick, overrides=overrides, sweeps=sweeps, on_run=progress,
                           scheduler=args.scheduler, workers=args.workers)
    out = Path(args.out)
    study.plot = str(plot_pareto(study.to_dict(), out / f"accuracy_{study.scene}.png"))
    text = json_text(study.to_dict())
    (out / f"accuracy_{study.scene}.json").write_text(text)
    print(text if args.json else "\n".join(table_lines(study)))
    return 0


def add_accuracy_parser(kinds) -> None:
    """Register ``study accuracy`` under the ``study`` subcommand group."""
    parser = kinds.add_parser("accuracy", help="accuracy versus wall time of the fidelity knobs of a scene")
    parser.add_argument("scene")
    parser.add_argument("--json", action="store_true", help="print the study as JSON")
    parser.add_argument("--out", default="results/accuracy", help="directory of the Pareto plot and JSON")
    parser.add_argument("--quick", action="store_true", help="two values per knob, wear ≤ 4 and COF ≤ 10 cycles")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="scene override for every run, e.g. procedure.cof_cycles=10 or motions.0.value=0.05 "
                             "(an entry of [[loads]] or [[motions]] by position or name; repeat)")
    parser.add_argument("--knob", action="append", default=[], metavar="NAME=V1,V2",
                        help="replace a knob's sweep, e.g. contact_size=3,4,6 (repeat)")
    add_cluster_arguments(parser)
    parser.set_defaults(func=cmd_accuracy)
