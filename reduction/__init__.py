"""Finite-element bodies and their reductions.

Meshes in (scikit-fem, meshio), sparse stiffness and mass out, then exact static
condensation onto retained DOFs and Craig-Bampton reduction for the multibody model.
Units: mm, N, MPa, t, s.

Modules, in the order data flows through them:
    mesh_io        read meshes with named node/element sets (Abaqus .inp, Gmsh .msh, scikit-fem)
    selection      pick nodes by plane, box, cylinder or points
    elasticity     assemble K (N/mm) and M (t): ElasticBody, node-interleaved DOFs
    coupling       RBE2 (kinematic) and RBE3 (distributing) couplings to reference points
    rbe3_condensation   condensed stiffness at RBE3 reference points (bolt bearing areas)
    body_loads     gravity, centrifugal, rigid-body and mode-shape inertia loads via M
    condensation   exact Schur complement onto retained DOFs, condensed loads, expansion
    craig_bampton  constraint modes + fixed-interface normal modes
    exudyn_bridge  floating-frame modes and ObjectFFRFreducedOrder for exudyn
    report         accuracy against the full model, records and error-vs-modes plot
    cache          HDF5 cache keyed by mesh, material, retained sets and mode count
    factorization, pardiso   sparse SPD solvers (MKL PARDISO, CHOLMOD, SuperLU)
"""
