"""Fixtures shared by several test files. Plain helpers (model builders, constants, checks) are in the
``support`` package beside this file (tests/support/); a fixture used by one file stays in that file.

Also imported by every rank of ``python -m mpi4py -m pytest tests/test_parallel.py``: nothing here is
collective or depends on the rank.
"""

import os

import pytest

# The helpers' asserts (support.local_problems.check_complementarity, support.images.assert_png) report their
# operands as a test's own do: rewritten by pytest like the test modules they came from.
pytest.register_assert_rewrite("support")


@pytest.fixture
def mpirun_env():
    """The environment of a child started with ``mpiexec``: Open MPI allowed to run as root and to put more
    ranks than cores on this machine, one BLAS thread per rank."""
    return dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                OPENBLAS_NUM_THREADS="1", OMPI_MCA_rmaps_base_oversubscribe="1")
