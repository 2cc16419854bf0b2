"""The ``fretwork`` command line."""
