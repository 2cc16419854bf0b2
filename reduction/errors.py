"""Errors raised for bad user input anywhere in fretwork."""


class InputError(ValueError):
    """Bad user input. The message names the item (key, file, set) and the problem in words."""
