"""The twin's FRF modes and calibrations against an independent lumped model, per catalogue axis.

    uv run python examples/frf_accuracy.py [--machine heavy_xy ...] [--excitation prbs ...]
        [--friction on --friction off] [--no-calibration] [--no-frf]

The oracle is tests/lumped_oracle.py: each ball-screw axis of a machine file in
examples/machines as three masses in a row written from the file's resolved values with the
catalogue formulas, discretized exactly (zero-order hold), not through the twin's transfer
function or MuJoCo.

FRF table: for each machine, axis, sensor (motor, table), excitation (PRBS, chirp, multisine)
and Coulomb friction (the file's, or none), `twin frf`'s default measurement (velocity loop on the
motor's encoder, 1 V, 16 s or --duration, to 1 kHz): each reported mode beside the lumped model's, its error,
and `unreliable` where the FRF marks it so (coherence or nonlinear distortion, with the reason);
a model mode below 980 Hz that the measurement does not report is listed as missing.

Calibration table: for each machine and axis, a hidden variant (table +10 %, axial or nut
stiffness -15 %, viscous friction +20 %, and on mid_size_xy the torsion -20 %) made by the
lumped model from a 0.6 s open-loop PRBS as `twin excite` writes it, read on a 10 nm scale with
0.1 um of noise, Coulomb friction off; `twin calibrate`'s fit, each value's error beside its
stated standard error (noise and model together, and apart) and the error in stated errors.
"""

import argparse
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))  # the independent oracle lives beside the tests

from lumped_oracle import MACHINES, modes, oracle, zoh_trace  # noqa: E402

from twin.commissioning.calibration import calibrate, excitation_trace, write_table  # noqa: E402
from twin.commissioning.frf import FrfSettings, measure  # noqa: E402
from twin.machines import build  # noqa: E402

CATALOGUE = ("compact_xy", "mid_size_xy", "heavy_xy", "sgm7j_xy", "sgm7j_axis")
EXCITATIONS = ("prbs", "chirp", "multisine")
#: Modes the measurement covers: below the band's top (1 kHz) less the peak's flank.
TOP_HZ = 980.0
#: A multisine's shortest record (s): four realizations of three 0.82 s periods.
SHORTEST_MULTISINE_S = 9.9
#: The measured trace's scale resolution and white noise (m).
SCALE_M = 1e-8
NOISE_M = 1e-7


def no_friction(axes: list[str]) -> dict[str, float]:
    return {f"{a}_friction_coulomb_N": 0.0 for a in axes}


def frf_rows(
    machine: str, axes: list[str], excitations: list[str], frictions: list[str], duration_s: float
) -> list[dict]:
    """One row per axis, sensor, excitation and friction: the reported modes against the oracle's
    (a multisine over at least its shortest record)."""
    rows = []
    for friction in frictions:
        overrides = None if friction == "on" else no_friction(axes)
        for axis in axes:
            system, _ = oracle(machine, axis, overrides)
            for sensor in ("motor", "table"):
                resonances, antiresonances = modes(system, sensor)
                for excitation in excitations:
                    r = measure(
                        str(MACHINES / f"{machine}.toml"),
                        FrfSettings(
                            axis=axis,
                            sensor=sensor,
                            excitation=excitation,
                            duration_s=max(duration_s, SHORTEST_MULTISINE_S)
                            if excitation == "multisine"
                            else duration_s,
                        ),
                        overrides,
                    )
                    expected = {"resonance": resonances, "antiresonance": antiresonances if sensor == "motor" else []}
                    found = []
                    for q in r.modes:
                        truth = min(expected[q.kind], key=lambda f: abs(f - q.frequency_hz), default=math.nan)
                        found.append(
                            {**q.to_json(), "model_hz": truth, "error_pct": 100 * (q.frequency_hz / truth - 1)}
                        )
                    missing = [
                        (kind, f)
                        for kind, fs in expected.items()
                        for f in fs
                        if f < TOP_HZ
                        and not any(q["kind"] == kind and abs(q["frequency_hz"] / f - 1) < 0.05 for q in found)
                    ]
                    rows.append(
                        {
                            "machine": machine,
                            "axis": axis,
                            "sensor": sensor,
                            "excitation": excitation,
                            "friction": friction,
                            "modes": found,
                            "missing": missing,
                            "incoherent_bands_hz": r.incoherent_bands_hz,
                        }
                    )
                    print_frf_row(rows[-1])
    return rows


def print_frf_row(row: dict) -> None:
    reliable = [abs(q["error_pct"]) for q in row["modes"] if q["unreliable"] is None]
    flagged = sum(q["unreliable"] is not None for q in row["modes"])
    cells = [
        f"{'R' if q['kind'] == 'resonance' else 'A'} {q['frequency_hz']:.2f}/{q['model_hz']:.2f} "
        f"{q['error_pct']:+.2f}% c{q['coherence']:.3f}" + ("!" if q["unreliable"] is not None else "")
        for q in row["modes"]
    ]
    cells += [
        f"{'R' if kind == 'resonance' else 'A'} missing {f:.2f}"
        + (
            " (incoherent band within 5 %)"
            if any(lo <= 1.05 * f and hi >= f / 1.05 for lo, hi in row["incoherent_bands_hz"])
            else ""
        )
        for kind, f in row["missing"]
    ]
    worst = f"{max(reliable):.2f}" if reliable else "-"
    print(
        f"{row['machine']:<11} {row['axis']} {row['sensor']:<5} {row['excitation']:<9} {row['friction']:<3} "
        f"max|err| {worst:>5} % flagged {flagged}  " + "; ".join(cells),
        flush=True,
    )


def hidden_variant(machine: str, axis: str) -> dict[str, float]:
    """The axis's table +10 %, axial (nut) stiffness -15 %, viscous friction +20 % and, where
    the torsion's mode lies inside the excitation's band, its torsion -20 %."""
    params = build(str(MACHINES / f"{machine}.toml")).params
    stiffness = f"{axis}_k_nut_N_per_m" if f"{axis}_k_nut_N_per_m" in params else f"{axis}_k_axial_N_per_m"
    hidden = {
        f"{axis}_table_mass_kg": 1.1 * params[f"{axis}_table_mass_kg"],
        stiffness: 0.85 * params[stiffness],
        f"{axis}_friction_viscous_N_s_per_m": 1.2 * params[f"{axis}_friction_viscous_N_s_per_m"],
    }
    if machine == "mid_size_xy":
        hidden[f"{axis}_k_torsion_N_m_per_rad"] = 0.8 * params[f"{axis}_k_torsion_N_m_per_rad"]
    return hidden


def calibration_rows(machine: str, axes: list[str], folder: Path) -> list[dict]:
    """For each axis: the hidden variant's lumped-model trace fitted by `twin calibrate`."""
    rows = []
    path = str(MACHINES / f"{machine}.toml")
    off = no_friction(axes)
    for axis in axes:
        hidden = hidden_variant(machine, axis)
        columns = excitation_trace(path, axis, overrides=off)
        system, delay = oracle(machine, axis, {**off, **hidden})
        y = zoh_trace(system, columns[f"u_{axis}_V"], 1e-4, delay)
        y = y + np.random.default_rng(0).normal(0.0, NOISE_M, len(y))
        columns[f"pos_{axis}_m"] = np.round(y / SCALE_M) * SCALE_M
        trace = folder / f"{machine}_{axis}.parquet"
        write_table(columns, trace)
        r = calibrate(path, trace, list(hidden), overrides=off, axis=axis)
        for name, truth in hidden.items():
            error = r.fitted[name] - truth
            stated = r.standard_errors.get(name, math.nan)
            row = {
                "machine": machine,
                "axis": axis,
                "parameter": name,
                "error_pct": 100 * error / truth,
                "stated_pct": 100 * stated / truth,
                "noise_pct": 100 * r.statistical_errors.get(name, math.nan) / truth,
                "model_pct": 100 * r.model_errors.get(name, math.nan) / truth,
                "in_stated": abs(error) / stated,
                "poorly_determined": name in r.poorly_determined,
            }
            rows.append(row)
            print(
                f"{machine:<11} {axis} {name[2:]:<28} error {row['error_pct']:+8.3f} %  "
                f"stated +-{row['stated_pct']:.3f} % "
                f"(noise {row['noise_pct']:.3f}, model {row['model_pct']:.3f})  {row['in_stated']:5.2f} errors"
                + ("  poorly determined" if row["poorly_determined"] else ""),
                flush=True,
            )
    return rows


def main(
    machines: list[str], excitations: list[str], frictions: list[str], frf: bool, calibration: bool, duration_s: float
) -> dict:
    out: dict = {"frf": [], "calibration": []}
    if frf:
        print(
            "FRF modes against the lumped model: measured/model Hz, error, the lowest coherence within 5 %, "
            "! marked unreliable"
        )
        for machine in machines:
            axes = [a.name for a in build(str(MACHINES / f"{machine}.toml")).axes]
            out["frf"] += frf_rows(machine, axes, excitations, frictions, duration_s)
    if calibration:
        print("Calibration of hidden variants made by the lumped model (error beside the stated standard error):")
        with tempfile.TemporaryDirectory() as folder:
            for machine in machines:
                axes = [a.name for a in build(str(MACHINES / f"{machine}.toml")).axes]
                out["calibration"] += calibration_rows(machine, axes, Path(folder))
    return out


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--machine", action="append", choices=CATALOGUE, help="repeat; default: all")
    parser.add_argument("--excitation", action="append", choices=EXCITATIONS, help="repeat; default: all")
    parser.add_argument("--friction", action="append", choices=("on", "off"), help="repeat; default: both")
    parser.add_argument("--duration", type=float, default=16.0, help="recorded time (s), a multisine's at least 9.9")
    parser.add_argument("--no-frf", action="store_true", help="skip the FRF table")
    parser.add_argument("--no-calibration", action="store_true", help="skip the calibration table")
    a = parser.parse_args()
    main(
        a.machine or list(CATALOGUE),
        a.excitation or list(EXCITATIONS),
        a.friction or ["off", "on"],
        not a.no_frf,
        not a.no_calibration,
        a.duration,
    )
