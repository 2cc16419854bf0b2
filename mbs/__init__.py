"""Flexible multibody models (exudyn) that produce interface motion and acceleration histories."""
