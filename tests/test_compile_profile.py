"""compile_kernels --profile: what compiling the kernels cost, kernel by kernel."""

import numba
import numpy as np
import pytest

from pedi_drake.apps.compile_kernels import compile_profile, main


def _fresh_kernels():
    """A kernel calling another, new objects each time (not cached): both compile when called."""

    @numba.njit(cache=False)
    def inner(x):
        return 2.0 * x

    @numba.njit(cache=False)
    def outer(x):
        return inner(x) + 1.0

    return inner, outer


def test_a_kernel_compiled_from_python_is_listed_with_its_callees_time():
    inner, outer = _fresh_kernels()

    def work():
        outer(1.0)
        outer(np.ones(2))

    rows = compile_profile(work)
    names = [row.kernel for row in rows]
    (row,) = [row for row in rows if row.kernel.endswith("outer")]
    assert row.signatures == 2 and row.seconds > 0.0
    # inner was compiled only from inside outer's compilation: not a row of its own.
    assert not any(name.endswith("inner") for name in names)
    assert len(inner.signatures) == 2


def test_a_kernel_called_from_python_itself_gets_a_row_of_its_own():
    inner, outer = _fresh_kernels()
    rows = compile_profile(lambda: (inner(1.0), outer(1.0)))
    counts = {row.kernel.rsplit(".", 1)[-1]: row.signatures for row in rows}
    # outer finds inner already compiled for a float: nothing of inner's inside outer's row.
    assert counts == {"inner": 1, "outer": 1}
    assert [row.seconds for row in rows] == sorted((row.seconds for row in rows), reverse=True)


def test_nothing_compiled_gives_no_rows():
    assert compile_profile(lambda: None) == []


def test_a_misspelt_option_exits_2(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--profil"])
    assert stop.value.code == 2
    assert "--profil" in capsys.readouterr().err
