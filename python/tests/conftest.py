"""Shared settings of the Python tests (run by CTest as test_python, with SEM_LIBRARY at the
build's libsem.so and PYTHONPATH at python/; see cmake/sem_tests_library.cmake)."""
import os
import tempfile

import pytest

SOURCE_DIR = os.environ.get("SEM_SOURCE_DIR",
                            os.path.dirname(os.path.dirname(os.path.dirname(__file__))))
SHARED_MODELS = os.environ.get("SEM_SHARED_MODELS", os.path.join(SOURCE_DIR, "..", "shared",
                                                                    "models"))


@pytest.fixture
def outdir():
    base = os.environ.get("SEM_TEST_OUTPUT")
    if base:
        os.makedirs(base, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=base) as d:
        yield d


def shared_model(relative):
    path = os.path.join(SHARED_MODELS, relative)
    if not os.path.exists(path):
        pytest.skip("shared model %s not found (SEM_SHARED_MODELS)" % relative)
    return path
