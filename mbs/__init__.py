"""Flexible multibody models (exudyn) that produce interface motion and acceleration histories.

Modules: counterweight (CW block mesh + Craig-Bampton reduction), parameters (model dataclasses),
excitation (gas-torque orders, gear mesh), model (exudyn crank throw with CB counterweights,
simulate, system eigenfrequencies), spectra (FFT, order spectrum, peak frequency), campbell,
results (HDF5 /histories, acceleration field), plots, run (one complete run), sweep (engine-speed
sweep), scene ([mbs] table of a scene), cli (sweep and mbs sub-commands). See mbs/NOTES.md.
"""
