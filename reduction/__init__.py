"""Finite-element bodies and their reductions.

Meshes in (scikit-fem, meshio), sparse stiffness and mass out, then exact static
condensation onto retained DOFs and Craig-Bampton reduction for the multibody model.
Units: mm, N, MPa, t, s.
"""
