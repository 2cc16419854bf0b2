"""``fretwork export-fmu RESULTS -o FILE.fmu``: the command line of the FMU export."""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path
from typing import Sequence

from reduction.errors import InputError
from pipelines.fmu.export import SourceOnlyFmuWarning, export_fmu


def add_export_fmu_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``export-fmu`` on a subparsers object; the handler is set as ``func``."""
    parser = subparsers.add_parser(
        "export-fmu",
        help="export load histories as a co-simulation FMU",
        description="Export the /histories of a results file (the run.h5 of `fretwork mbs`, or the "
        "results.h5 of a coupled `fretwork run`) as a co-simulation FMU whose outputs play "
        "the histories back (linear interpolation, parameters time_offset, periodic, period). "
        "Both play the steady part of the multibody run, where its wing amplitude is measured: of a "
        "run.h5 its second half (--whole: the whole run, start-up transient included); a coupled run "
        "stores only that part, scaled as its load cycle used it. The FMU file (*.fmu) replaces no "
        "file but an FMU that fretwork wrote.",
    )
    _configure_parser(parser)
    return parser


def _configure_parser(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("results", type=Path,
                        help="results file (HDF5) with a /histories group, or a run's output folder: of "
                        "`fretwork mbs` (its run.h5) or of a coupled `fretwork run` (its results.h5)")
    parser.add_argument(
        "--signals", nargs="+", metavar="NAME",
        help="signals to export (names under /histories, space or comma separated); default: all",
    )
    parser.add_argument("--fmi", type=int, choices=(2, 3), default=2, help="FMI version (default 2)")
    parser.add_argument("-o", "--output", type=Path, required=True,
                        help="FMU file to write, named *.fmu, e.g. loads.fmu; an existing file is replaced only "
                        "if it is an FMU that fretwork wrote, never the results file")
    parser.add_argument("--whole", action="store_true",
                        help="of an mbs run.h5, export the whole run, its start-up transient included (default: "
                        "its steady second half, where the wing amplitude is measured)")
    parser.add_argument("--model-name", help="model name (default: output file name)")
    parser.set_defaults(func=run_export_fmu)


def run_export_fmu(args: argparse.Namespace) -> int:
    """Run ``export-fmu`` from parsed arguments; prints the result. Returns the exit code (2: bad input)."""
    signals = None
    if args.signals:
        signals = [name for item in args.signals for name in item.split(",") if name]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", SourceOnlyFmuWarning)
        try:
            path = export_fmu(args.results, args.output, signals, args.fmi, whole=args.whole,
                              model_name=args.model_name)
        except InputError as error:
            print(f"fretwork: error: {error}", file=sys.stderr)
            return 2
    for warning in caught:
        print(f"fretwork: warning: {warning.message}", file=sys.stderr)
    content = "sources only, no binary" if caught else "binary and sources"
    print(f"wrote {path} (FMI {args.fmi}.0 co-simulation, {content}, {path.stat().st_size / 1e6:.2f} MB)")
    return 0


def main_export(argv: Sequence[str] | None = None) -> int:
    """Stand-alone entry: ``python -m pipelines.fmu.cli RESULTS.h5 [--signals ...] [--fmi 2|3] [--whole]
    -o loads.fmu``."""
    parser = argparse.ArgumentParser(prog="fretwork export-fmu", description="Export load histories as an FMU.")
    _configure_parser(parser)
    return run_export_fmu(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main_export())
