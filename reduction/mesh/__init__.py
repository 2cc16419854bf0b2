"""Meshes: reading files with named sets, the shipped generators, node selection, surface motion."""
