"""The milling forces on the workpiece as ``[[disturbances]]`` kinds: ``end_milling`` (the
mechanistic model, :class:`~twin.machining.cutting.EndMilling`) and ``average_force`` (Choi
1999's, :class:`~twin.machining.cutting.AverageForce`), their specs and builders."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, PositiveFloat

from twin.disturbances.kinds import DisturbanceSpecBase, register
from twin.machining.cutting import (
    MAX_FLUTES,
    MAX_HELIX_DEG,
    MIN_SPINDLE_RPM,
    AverageForce,
    EndMilling,
    WorkMaterialSpec,
)
from twin.machining.tool_dynamics import ToolDynamicsSpec


class EndMillingSpec(DisturbanceSpecBase, WorkMaterialSpec):
    """end_milling: the mechanistic milling force on the workpiece (EndMilling), driven by its motion."""

    type: Literal["end_milling"]
    spindle_rpm: float = Field(ge=MIN_SPINDLE_RPM, description="rev/min; at least 1 (a tooth period of at most 60 s)")
    n_flutes: int = Field(ge=1, le=MAX_FLUTES, description="teeth of the cutter")
    diameter_mm: PositiveFloat = Field(description="cutter diameter, mm")
    axial_depth_mm: PositiveFloat = Field(description="axial depth of cut, mm")
    radial_depth_mm: PositiveFloat = Field(description="radial depth of cut (the diameter: a slot), mm")
    mode: Literal["up", "down"] = Field("up", description="up (conventional) or down (climb) milling")
    start_s: float = Field(0.0, ge=0, description="the cut starts, s")
    stop_s: PositiveFloat | None = Field(None, description="the cut stops, s (default: never)")
    spindle_phase_rad: float | None = Field(None, description="None: drawn from the seed")
    seed: int | None = Field(None, ge=0, description="default: the scenario's seed")
    helix_deg: float = Field(0.0, ge=0.0, lt=MAX_HELIX_DEG, description="helix angle of the flutes, deg (0: straight)")
    dynamics: ToolDynamicsSpec | None = Field(
        None, description="the structure at the tool tip: modes in X/Y or a measured FRF (twin.machining.tool_dynamics)"
    )


class AverageForceSpec(DisturbanceSpecBase):
    """average_force: Choi 1999's average cutting force k_il v + k_c (z x v) (AverageForce)."""

    type: Literal["average_force"]
    k_il_N_s_per_m: float = Field(-2500.0, description="force along the velocity per velocity, N s/m")
    k_c_N_s_per_m: float = Field(2500.0, description="force across the velocity per velocity, N s/m")
    harmonic_fraction: float = Field(0.0, ge=0, le=0.2, description="tooth-passing harmonic, a fraction of the force")
    spindle_rpm: float = Field(10000.0, ge=MIN_SPINDLE_RPM, description="rev/min (sets the tooth frequency)")
    n_flutes: int = Field(2, ge=1, le=MAX_FLUTES, description="teeth of the cutter")
    start_s: float = Field(0.0, ge=0, description="the cut starts, s")
    stop_s: PositiveFloat | None = Field(None, description="the cut stops, s (default: never)")
    harmonic_phase_rad: float | None = Field(None, description="None: drawn from the seed")
    seed: int | None = Field(None, ge=0, description="default: the scenario's seed")


def _end_milling_from(spec: EndMillingSpec, axis_names: list[str], seed: int, field: str) -> EndMilling:
    return EndMilling(
        spindle_rpm=spec.spindle_rpm,
        n_flutes=spec.n_flutes,
        diameter_mm=spec.diameter_mm,
        axial_depth_mm=spec.axial_depth_mm,
        radial_depth_mm=spec.radial_depth_mm,
        mode=spec.mode,
        coefficients=spec.cutting_coefficients(),
        start_s=spec.start_s,
        stop_s=spec.stop_s,
        spindle_phase_rad=spec.spindle_phase_rad,
        seed=seed,
        helix_deg=spec.helix_deg,
        dynamics=spec.dynamics,
    )


def _average_force_from(spec: AverageForceSpec, axis_names: list[str], seed: int, field: str) -> AverageForce:
    return AverageForce(
        spec.k_il_N_s_per_m,
        spec.k_c_N_s_per_m,
        spec.harmonic_fraction,
        spec.spindle_rpm,
        spec.n_flutes,
        spec.start_s,
        spec.stop_s,
        spec.harmonic_phase_rad,
        seed,
    )


register("end_milling", EndMillingSpec, _end_milling_from)
register("average_force", AverageForceSpec, _average_force_from)
