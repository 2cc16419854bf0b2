"""Flexible multibody model (exudyn) of a crank throw with bolted counterweights: histories in.

Modules, in the order data flows through them:
    parameters     model dataclasses (throw, counterweight, excitation, solver); scene  the [mbs] table
    refusal        a parameter refused: its fields, values and what is allowed (scene names the keys)
    counterweight  generic CW mesh (its shape from reduction.mesh.generators) + Craig-Bampton reduction
    flexible_throw Craig-Bampton crank throw (the flexible_crankshaft effect); joint  CW-web joint stiffness
    excitation     gas-torque orders and gear mesh
    items          the exudyn items of the model (throws, bearings, drive, CWs, loads, sensors)
    model          reduce_bodies (once per run), simulate at fixed step, eigen-analyses
    histories      RunHistories and the one definition of the wing amplitude (steady state)
    loading        what one CW's contact model takes from a run, and its load cycle
    spectra, campbell   FFT / order spectra, Campbell diagram
    results, plots run.h5 (/histories), PNGs;  run  one complete run;  sweep  per-speed cases
See mbs/NOTES.md. Units: mm, N, t, s, rad.
"""
