"""Studies that compare several runs of a scene: accuracy versus cost, constant versus variable
COF, mesh convergence."""
