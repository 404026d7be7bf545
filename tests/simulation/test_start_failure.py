"""A law that raises before the first step (while the consistent start is found) is a clear
SimulationError naming the component, the law and the time -- not a traceback from inside the
assembler -- and a law that only fails later still integrates up to where it fails."""
import pytest

import mbcomp
from conftest import torque_pendulum


def table_from_one_second(t, phi, w):
    """A torque table that starts at t = 1 s (a user's off-by-one in the table range)."""
    if t < 1.0:
        raise ValueError(f"no torque tabulated at t={t:g} s")
    return 0.0


@pytest.mark.parametrize("method", ["RK45", "radau5"])
def test_a_law_failing_at_the_start_names_component_law_and_time(method):
    with pytest.raises(mbcomp.SimulationError) as info:
        mbcomp.simulate(torque_pendulum(table_from_one_second), t_end=2.0, method=method)
    msg = str(info.value)
    assert msg.startswith("Torque 'motor': table_from_one_second raised ValueError at t=0:")
    assert "test_start_failure.py" in msg and "nothing was integrated" in msg
    assert isinstance(info.value.__cause__, ValueError)  # the law's own exception is kept


def test_a_law_failing_later_keeps_the_run_up_to_there():
    def table_to_one_second(t, phi, w):
        if t > 1.0:
            raise ValueError(f"no torque tabulated at t={t:g} s")
        return 0.0

    res = mbcomp.simulate(torque_pendulum(table_to_one_second), t_end=2.0, n_out=201)
    assert res.status == "failed" and "table_to_one_second raised ValueError" in res.message
    assert 0.9 < res.time[-1] <= 1.0
