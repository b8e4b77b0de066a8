"""Shared paths and data of the Python tests (run from any directory)."""

import os
from pathlib import Path

import numpy as np
import pytest

import hystcomp

ROOT = Path(__file__).resolve().parents[3]
MODELS = ROOT / "models"
TABLE1_FILE = MODELS / "table1-plant.json"
TABLE2_FILE = MODELS / "table2-inverse.json"
# The shared real data beside the repository, or where HYSTCOMP_SHARED_DATA points (as in the
# Rust tests, hystcomp-testkit); a test that needs it and finds it absent is skipped, and the
# Rust runner (tests/python.rs) records the skip where CI shows it.
DBO_DATA = Path(os.environ.get("HYSTCOMP_SHARED_DATA", ROOT.parent / "shared" / "data")) / "dbo-micromanipulator"


@pytest.fixture
def table1():
    """The Table 1 plant model file (V -> um)."""
    return hystcomp.ModelFile.load(TABLE1_FILE)


@pytest.fixture
def table2():
    """The Table 2 inverse model file (um -> V)."""
    return hystcomp.ModelFile.load(TABLE2_FILE)


def table1_record(samples=4000):
    """A decaying 1 Hz sine at 200 Hz, 0..10 V, through the Table 1 model: (volts, um)."""
    t = np.arange(samples) / 200.0
    volts = 5.0 - 5.0 * np.exp(-t / 10.0) * np.cos(2 * np.pi * t)
    lo, hi = volts.min(), volts.max()
    plant = hystcomp.Mpim.table1()
    um = 75.0 * plant.process((volts - lo) / (hi - lo))
    return volts, um
