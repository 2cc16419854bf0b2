"""Contact mechanics on condensed interfaces.

The paper's contact law (penalty normal with wear as a gap, elastic-stick friction, COF
evolution by frictional dissipation, Archard wear) lives in :mod:`contact.law` and nowhere
else. Units: mm, N, MPa, t, s, mJ.

Modules, in the order data flows through them:
    interface      pair the surfaces into contact points (node-to-node, node-to-segment)
    mortar         dual-mortar pairing of non-matching surfaces
    bolts          axial bolt elements: pretension, then locked
    assembly       condense the bodies onto the interface and the control DOFs
    structure      the condensed structure and its contact space
    law            the contact law, pure and vectorised (eqs. 1-8)
    linear, solver Newton iteration with cutbacks on the condensed system
    sliding        finite sliding: re-pairing as the bodies slide, each body's own wear field
    cycle_jump     the adaptive cycle jump of the wear phase
    procedure      preload, COF phase, wear phase: a run and its typed ending
    tabulated      load programs that follow tabulated histories (multibody-driven)
    verdict        cycle figures, active slip, loosening, the verdict and the Ending
    energy, checks energy bookkeeping, consistent-tangent check
    full_model     the uncondensed reference model
"""
