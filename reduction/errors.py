"""Errors raised for bad user input anywhere in fretwork, and the wording of their messages."""


class InputError(ValueError):
    """Bad user input. The message names the item (key, file, set) and the problem in words."""


def listed(words: list[str]) -> str:
    """Words of a message as a list in prose: "a", "a and b", "a, b and c"."""
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " and " + words[-1]
