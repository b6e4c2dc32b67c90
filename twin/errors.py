"""Errors the twin raises for bad input and for simulations that go wrong."""


class TwinInputError(ValueError):
    """Bad user input: names the field and the offending value.

    The CLI prints the message on one line and exits with code 2.
    """

    def __init__(self, field: str, value, reason: str):
        self.field = field
        self.value = value
        self.reason = reason
        super().__init__(f"{field} = {value!r}: {reason}")


class SimulationDiverged(RuntimeError):
    """The physics blew up (non-finite state, MuJoCo instability warning or runaway).

    Attributes
    ----------
    sim_time_s : float
        Simulated time (s) at which the divergence was detected.
    """

    def __init__(self, sim_time_s: float, reason: str):
        self.sim_time_s = sim_time_s
        self.reason = reason
        super().__init__(f"simulation diverged at t = {sim_time_s:.6f} s: {reason}")
