"""Outputs of a contact run: results file, checkpoints, ParaView files, plots."""
