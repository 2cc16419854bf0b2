"""Export of load histories as a Functional Mock-up Unit (FMI 2 / FMI 3 co-simulation)."""
