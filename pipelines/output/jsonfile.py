"""Strict JSON for what fretwork prints (``--json``) and writes (``summary.json``, ``limit.json``
and the commands' other JSON files): :func:`json_text`."""

import json
import math

import numpy as np


def _finite(value):
    """``value`` with every non-finite float (inf, NaN) as None: JSON has no Infinity or NaN,
    and a strict reader refuses them."""
    if isinstance(value, dict):
        return {key: _finite(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(item) for item in value]
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    return value


def json_text(value) -> str:
    """``value`` as strict JSON, indented: non-finite floats as null."""
    return json.dumps(_finite(value), indent=2, default=float, allow_nan=False)
