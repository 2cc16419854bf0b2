"""Shared reduced counterweights (meshing and the sparse eigen-solve take about a second each)."""

import pytest

from mbs.counterweight import CounterweightGeometry, reduce_counterweight


@pytest.fixture(scope="session")
def reduced_cw4():
    return reduce_counterweight(CounterweightGeometry(), n_modes=4)
