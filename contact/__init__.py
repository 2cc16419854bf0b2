"""Contact mechanics on condensed interfaces.

The paper's contact law (penalty normal with wear as a gap, elastic-stick friction, COF
evolution by frictional dissipation, Archard wear) lives in :mod:`contact.law` and nowhere
else. :mod:`contact.interface` pairs surfaces into contact points; :mod:`contact.solver`
owns the Newton iteration on the condensed system. Units: mm, N, MPa, t, s, mJ.
"""
