"""A multibody parameter refused, with the fields it concerns, their values and what is allowed.

The parameter dataclasses (:mod:`mbs.parameters`, :class:`mbs.counterweight.CounterweightGeometry`)
raise :class:`Refusal`; the scene reader (:mod:`mbs.scene`) names its fields as the user wrote
them (``[mbs] n_modes``, ``[mbs.solver] time_step``) from the typed fields, not from the text.
"""

from __future__ import annotations

from reduction.errors import InputError


def shown(value) -> str:
    """A value as a scene (TOML) writes it: lists for tuples and sets, numbers and strings as given."""
    if isinstance(value, (tuple, list)):
        return "[" + ", ".join(shown(v) for v in value) + "]"
    if isinstance(value, (set, frozenset)):
        return shown(sorted(value))
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    return repr(value) if isinstance(value, float) else str(value)


class Refusal(InputError):
    """``fields``: the ModelParams fields at fault, dotted within ModelParams ('n_modes',
    'solver.time_step'), the first the one refused, the others those its bound comes from;
    ``values``: their values; ``allowed``: what is allowed, a phrase that reads after any of them
    ("must be a whole number of at least 1 (Craig-Bampton modes per counterweight)")."""

    def __init__(self, fields: tuple[str, ...], values: tuple, allowed: str):
        self.fields, self.values, self.allowed = tuple(fields), tuple(values), allowed
        named = " and ".join(f"{field} = {shown(value)}" for field, value in zip(self.fields, self.values))
        super().__init__(f"{named}: {allowed}")


def refuse(field: str, value, allowed: str) -> Refusal:
    """The refusal of one field's value."""
    return Refusal((field,), (value,), allowed)
