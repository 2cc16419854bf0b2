"""Thin orchestration: scenes, runs, results files, plots and the `fretwork` command line."""
