"""The ``fretwork`` command line. Bad input: one clear message on stderr, exit status 2."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from reduction.errors import InputError

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def _json(value) -> str:
    return json.dumps(value, indent=2, default=float)


def cmd_run(args) -> int:
    from pipelines import scene
    from pipelines.run import run_scene

    loaded = scene.load(args.scene)
    outcome = run_scene(loaded, args.out, progress=not args.quiet)
    if args.json:
        print(_json(outcome.summary))
    else:
        print(_human_summary(outcome))
    return 0


def _human_summary(outcome) -> str:
    s = outcome.summary
    lines = [f"scene {s['scene']}: verdict {s['verdict'].upper()}"
             f"{'' if s['stationary'] else ' (not yet stationary)'} after {s['cycles_run']} cycles",
             f"  stick {s['stick_area_fraction']:.1%}, slip {s['slip_area_fraction']:.1%}, "
             f"damaged {s['damaged_area_fraction']:.1%} of the nominal contact area",
             f"  max wear depth {s['max_wear_depth_mm'] * 1000:.2f} µm, dissipated {s['dissipated_energy_mJ']:.4g} mJ"]
    if s.get("min_stick_margin") is not None:
        lines.append(f"  smallest safety margin of stuck points: {s['min_stick_margin']:.3f}")
    lines.append(f"  results: {outcome.results_path}")
    if outcome.plots:
        lines.append(f"  plots:   {Path(outcome.plots[0]).parent}")
    return "\n".join(lines)


def cmd_validate(args) -> int:
    from pipelines.validate import run_validation

    records = run_validation(quick=args.quick, out_dir=Path(args.out), progress=not args.json)
    if args.json:
        print(_json(records))
    else:
        for r in records:
            mark = "PASS" if r["passed"] else "FAIL"
            print(f"{mark}  {r['case']:<28} {r['quantity']:<34} value {r['value']:.6g}  "
                  f"reference {r['reference']:.6g}  error {r['rel_error']:.2e} (tol {r['tolerance']:g})")
    return 0 if all(r["passed"] for r in records) else 1


def cmd_demo(args) -> int:
    from pipelines import scene
    from pipelines.run import run_scene

    loaded = scene.load(EXAMPLES / "cylinder_on_plane.toml")
    outcome = run_scene(loaded, args.out, progress=True)
    print(_human_summary(outcome))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="fretwork", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run a scene file")
    run.add_argument("scene")
    run.add_argument("--out", required=True, help="output directory")
    run.add_argument("--json", action="store_true", help="print the global figures as JSON")
    run.add_argument("--quiet", action="store_true", help="no progress bar")
    run.set_defaults(func=cmd_run)
    validate = sub.add_parser("validate", help="validation against closed forms and reference models")
    validate.add_argument("--json", action="store_true")
    validate.add_argument("--quick", action="store_true", help="coarser settings (CI)")
    validate.add_argument("--out", default="results/validation")
    validate.set_defaults(func=cmd_validate)
    demo = sub.add_parser("demo", help="run the main job on the built-in default scene")
    demo.add_argument("--out", default="results/demo")
    demo.set_defaults(func=cmd_demo)
    from pipelines.fmu import add_export_fmu_parser
    add_export_fmu_parser(sub)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except InputError as error:
        print(f"fretwork: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("fretwork: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
