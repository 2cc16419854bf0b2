"""Finite-element bodies and their reductions.

Meshes in (scikit-fem, meshio), sparse stiffness and mass out, then exact static
condensation onto retained DOFs and Craig-Bampton reduction for the multibody model.
Units: mm, N, MPa, t, s.

Modules, in the order data flows through them:
    mesh.io        read meshes with named node/element sets (Abaqus .inp, Gmsh .msh, scikit-fem)
    mesh.generators  the shipped meshes (cylinder, plane, blocks, beam with hole, CW and web blocks)
    mesh.selection   pick nodes and facets by plane, box, ring, cylinder, points or named set
    mesh.motion      move surface nodes, the interior following harmonically
    elasticity     assemble K (N/mm) and M (t): ElasticBody, node-interleaved DOFs
    coupling       RBE2 (kinematic) and RBE3 (distributing) couplings to reference points
    rbe3_condensation   condensed stiffness at RBE3 reference points (bolt bearing areas)
    body_loads     gravity, centrifugal, rigid-body and mode-shape inertia loads via M
    modal_loads    loads from another model's modes: inertia patterns, wing-mode load
    condensation   exact Schur complement onto retained DOFs, condensed loads, expansion
    craig_bampton  constraint modes + fixed-interface normal modes
    exudyn_bridge  floating-frame modes and ObjectFFRFreducedOrder for exudyn
    report         accuracy against the full model, records and error-vs-modes plot
    factorization, pardiso   sparse SPD solvers (MKL PARDISO, CHOLMOD, SuperLU)
    threads                  one BLAS thread in the numerical steps: results independent of thread settings
"""
