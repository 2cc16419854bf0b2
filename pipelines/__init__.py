"""Orchestration: scenes in, runs, studies, results files, plots and the `fretwork` command line.

No physics lives here: each module wires the packages below (reduction, mbs, contact) together.

Modules and sub-packages, in the order data flows through them:
    scene/         TOML scene -> validated Scene (schema.py: keys, types, validation; checks.py:
                   cross-references)
    examples       the shipped scenes (package data; the repository's examples/ folder)
    coupling       the [coupling] table: multibody stage, CW inertia patterns, cycle program
    build          Scene -> Model: meshes, bodies, condensed assembly, law, program, procedure
    stages         the stage cache (content hash + code fingerprint)
    parallel       independent cases on dask (local cluster, a scheduler, or in process)
    jobs/          run, limit (scan: every change of verdict), margins, sweep, demo, validate
    studies/       accuracy versus cost (accuracy, knobs, accuracy_report), constant vs variable COF,
                   mesh convergence (convergence)
    output/        results.h5, checkpoints, ParaView files, plots
    fmu/           load histories as FMUs (table, description, export, cli)
    cli/           the `fretwork` command line (main, mbs, accuracy)
"""
