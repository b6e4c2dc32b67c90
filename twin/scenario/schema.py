"""The scenario file's schema (pydantic): a machine with parameter overrides, a controller per
axis (or one for all axes), a reference, the rates, the drive and sensor settings, disturbances,
a stock and its tools, inspected features and a seed.  Every field in SI unless its name says
otherwise."""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import Field, PositiveFloat

from twin.disturbances import DISTURBANCES, DisturbanceSpecBase
from twin.gcode.planner import PlannerSettings
from twin.machining.engagement import StockSpec, ToolSpec
from twin.machining.inspection import InspectSpec
from twin.references import REFERENCES, ReferenceSpecBase
from twin.spec import StrictSpec, tagged_union


class ObserverSpec(StrictSpec):
    """An observer add-on: a kind of ``controllers.OBSERVERS`` and its parameters (checked by
    the kind's own model)."""

    type: str
    params: dict[str, Any] = Field(default_factory=dict)


class ControllerSpec(StrictSpec):
    """One controller: a kind of ``controllers.CONTROLLERS``, its parameters (checked by the
    kind's own model), discretization, feedforward, an optional observer add-on and, for
    ``type = "sum"``, its parts."""

    type: str
    params: dict[str, Any] = Field(default_factory=dict)
    discretization: Literal["tustin", "zoh"] = "tustin"
    velocity_ff: float = Field(0.0, description="V per m/s of reference velocity")
    acceleration_ff: float = Field(0.0, description="V per m/s^2 of reference acceleration")
    observer: ObserverSpec | None = None
    parts: list[ControllerSpec] | None = Field(None, description="the summed controllers of type 'sum'")


#: The ``[reference]`` table: one spec per registered kind (:mod:`twin.references`), told apart by
#: ``type``; to a type checker, which cannot follow a union built at run time, the kinds' base.
if TYPE_CHECKING:
    ReferenceSpec = ReferenceSpecBase
else:
    ReferenceSpec = tagged_union(REFERENCES)


class DriveSpec(StrictSpec):
    saturation_V: PositiveFloat | None = None
    delay_s: float | None = Field(None, ge=0, le=10.0, description="default: the machine's delay; at most 10 s")


#: A sensor's resolution or noise at most (m): coarser than any scale or encoder of a machine tool.
MAX_SENSOR_M = 1e-3
#: A resolution or a noise's standard deviation (m), in [0, MAX_SENSOR_M].
SensorMetres = Annotated[float, Field(ge=0, le=MAX_SENSOR_M)]


class SensorSpec(StrictSpec):
    encoder_resolution_m: SensorMetres | list[SensorMetres] | None = Field(
        None, description="the table's scale, m; 0 for ideal; default: the machine's (0 for the papers' machines)"
    )
    motor_encoder_resolution_m: SensorMetres | list[SensorMetres] | None = Field(
        None, description="the motor's encoder in table travel, m; 0 for ideal; default: the machine's"
    )
    noise_std_m: SensorMetres | list[SensorMetres] = 0.0
    velocity: Literal["backward_difference", "tachometer"] = "backward_difference"
    feedback: Literal["dual", "table", "motor"] | None = Field(
        None,
        description="position on the table's scale and velocity on the motor's encoder (dual), both on the "
        "scale (table) or both on the motor (motor, a semi-closed loop); default: the machine's (dual for a "
        "machine file, table for the papers' machines)",
    )


#: The ``[[disturbances]]`` entries: one spec per registered kind (:mod:`twin.disturbances`), the same way.
if TYPE_CHECKING:
    DisturbanceSpec = DisturbanceSpecBase
else:
    DisturbanceSpec = tagged_union(DISTURBANCES)


#: Shortest physics step (s): 0.1 us, a thousand times finer than any mode of these drives needs.
MIN_TIMESTEP_S = 1e-7
#: Longest physics step (s): 10 ms, the order of the fastest mechanical time constants here.
MAX_TIMESTEP_S = 1e-2
#: Longest control period (s).
MAX_CONTROL_PERIOD_S = 1.0
#: ``[[inspect]]`` features at most.
MAX_FEATURES = 100


class Scenario(StrictSpec):
    """A closed-loop run; every field in SI unless its name says otherwise."""

    name: str = "scenario"
    description: str = ""
    machine: str
    overrides: dict[str, float] = Field(default_factory=dict)
    duration_s: PositiveFloat | None = Field(
        None, description="simulated time, s; default the reference's own end (a G-code program's cycle time)"
    )
    timestep_s: float | None = Field(
        None,
        ge=MIN_TIMESTEP_S,
        le=MAX_TIMESTEP_S,
        description="physics step, s; default the machine's (0.1 ms for the papers')",
    )
    control_period_s: float = Field(1e-3, ge=MIN_TIMESTEP_S, le=MAX_CONTROL_PERIOD_S)
    seed: int = Field(0, ge=0)
    record_every_ticks: int | None = Field(
        None, ge=0, description="record every Nth tick; 0: metrics only; default every tick up to 100 000 ticks"
    )
    controller: ControllerSpec | None = None
    controllers: dict[str, ControllerSpec] | None = None
    reference: ReferenceSpec
    drive: DriveSpec = DriveSpec()
    sensors: SensorSpec = SensorSpec()
    disturbances: list[DisturbanceSpec] = Field(default_factory=list)
    planner: PlannerSettings = PlannerSettings()
    stock: StockSpec | None = Field(None, description="a workpiece the G-code program cuts")
    tool: ToolSpec | None = Field(None, description="the cutter of a program without T words")
    tools: list[ToolSpec] = Field(default_factory=list, description="the cutters of a program, by T number")
    inspect: list[InspectSpec] = Field(
        default_factory=list, max_length=MAX_FEATURES, description="features of the part measured on the virtual part"
    )
