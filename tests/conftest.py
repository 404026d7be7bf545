import pathlib

import pytest

import mbcomp
from mbcomp.modeling.loader import import_file

ROOT = pathlib.Path(__file__).resolve().parents[1]


def load_model(relpath):
    """A model file (``models/...py``, relative to the repository root) as a module:
    :func:`mbcomp.load_model_file`, so the tests load models as users and the CLI do."""
    return mbcomp.load_model_file(ROOT / relpath)


def load_module(relpath):
    """Any Python file (relative to the repository root) as a module, build() or not."""
    return import_file(ROOT / relpath)


@pytest.fixture
def models_dir():
    return ROOT / "models"
