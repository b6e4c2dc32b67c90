"""The catalogue machines measured, calibrated and tuned with default settings.

    uv run python examples/catalogue_machines.py [--machine examples/machines/heavy_xy.toml ...]

For each machine file (default: the three example ball-screw tables): the modes of X and Y
measured by `twin frf` (velocity loop on the motor's encoder, PRBS to 1 kHz) beside the
model's; the calibration of a hidden variant (X's table +20 %, its nut's stiffness -30 %, its
viscous friction +20 %) from a 0.6 s open-loop PRBS on X, simulated by MuJoCo, read on a 10 nm
scale with 0.1 um of white noise, with each fitted value's error and standard error; and `twin tune`'s gains with
their margins over every crossing. `twin fidelity --machine FILE` and `twin run
examples/machines/<name>_part.toml` give the rest of the docs' table.
"""

import argparse
import tempfile
from pathlib import Path

import numpy as np

import twin
from twin.commissioning.calibration import write_table
from twin.machines import get_machine

EXAMPLES = Path(__file__).resolve().parent / "machines"
#: The measured trace's scale resolution and its white noise (m): a 10 nm scale, 0.1 um noise.
SCALE_M = 1e-8
NOISE_M = 1e-7
MACHINES = [EXAMPLES / "mid_size_xy.toml", EXAMPLES / "compact_xy.toml", EXAMPLES / "heavy_xy.toml"]


def hidden_variant(machine: str) -> dict[str, float]:
    """X's table +20 %, its axial stiffness (the nut's where the file computes it) -30 %, its
    viscous friction +20 %."""
    params = {k: p.value for k, p in get_machine(machine).parameters.items()}
    stiffness = "x_k_nut_N_per_m" if "x_k_nut_N_per_m" in params else "x_k_axial_N_per_m"
    return {
        "x_table_mass_kg": 1.2 * params["x_table_mass_kg"],
        stiffness: 0.7 * params[stiffness],
        "x_friction_viscous_N_s_per_m": 1.2 * params["x_friction_viscous_N_s_per_m"],
    }


def calibration(machine: str, folder: Path) -> dict:
    """The hidden variant's trace from MuJoCo, fitted; each value's relative error."""
    hidden = hidden_variant(machine)
    measured = twin.frf(
        machine, hidden, loop="open", excitation="prbs", amplitude_V=2.0, duration_s=3.3, f_max_hz=500.0
    ).run
    trace = folder / f"{Path(machine).stem}_trace.parquet"
    start = measured.t_s[np.flatnonzero(measured.u_applied_V[:, 0])[0]]  # after the FRF's settling
    first = measured.t_s < start + 0.6  # at rest until then; the open loop drifts: 0.6 s of it
    position = measured.table_position_m()[first, 0]
    noise = np.random.default_rng(0).normal(0.0, NOISE_M, len(position))
    columns = {
        "time_s": measured.t_s[first],
        "u_x_V": measured.u_applied_V[first, 0],
        "pos_x_m": np.round(position / SCALE_M) * SCALE_M + noise,  # as a scale reads it
    }
    write_table(columns, trace)
    result = twin.calibrate(machine, trace, list(hidden)).summary
    errors = {k: result["fitted"][k] / v - 1 for k, v in hidden.items() if k in result["fitted"]}
    return {
        "hidden": hidden,
        "fitted": result["fitted"],
        "errors": errors,
        "standard_errors": result["standard_errors"],
        "fit_index_pct": result["fit_index_pct"],
        "unidentifiable": result["unidentifiable"],
        "solver": result["solver"],
    }


def main(machines: list[str]) -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for machine in machines:
            row = {"machine": machine, "modes": {}}
            for axis in ("x", "y"):
                f = twin.frf(machine, axis=axis).summary
                row["modes"][axis] = (f["resonances_hz"], f["model_resonances_hz"])
            row["calibration"] = calibration(machine, Path(folder))
            row["tune"] = twin.tune(machine).summary
            rows.append(row)
            print(Path(machine).name)
            for axis, (measured, model) in row["modes"].items():
                print(
                    f"  modes {axis}: measured {np.round(measured, 1).tolist()} Hz, "
                    f"model {np.round(model, 1).tolist()} Hz"
                )
            c = row["calibration"]
            print(
                "  calibration of the hidden variant, fit index",
                f"{c['fit_index_pct']['after']:.3f} %, residual {c['solver']['residual_rms_m']:.3g} m RMS",
                f"(the trace's noise {c['solver']['noise_floor_m']:.3g} m):",
            )
            for k, v in c["hidden"].items():
                if k in c["fitted"]:
                    se = 100 * c["standard_errors"].get(k, float("nan")) / c["fitted"][k]
                    print(
                        f"    {k}: hidden {v:.5g}, fitted {c['fitted'][k]:.5g} "
                        f"({100 * c['errors'][k]:+.3f} %, standard error {se:.3f} %)"
                    )
                else:
                    print(f"    {k}: hidden {v:.5g}, not fitted: {c['unidentifiable'].get(k)}")
            for axis, design in row["tune"]["axes"].items():
                g, v, p = design["gains"], design["velocity_loop"], design["position_loop"]
                print(
                    f"  tune {axis} ({row['tune']['feedback']}): kp {g['kp_pos']:.4g} 1/s, "
                    f"kv {g['kp_vel']:.4g} V s/m, Ti {1e3 * g['ti_vel_s']:.3g} ms, notch {g['notch_hz']:.1f} Hz; "
                    f"velocity loop {v['crossover_hz']:.1f} Hz PM {v['phase_margin_deg']:.1f} deg "
                    f"GM {v['gain_margin_db']:.2f} dB at {v['gain_margin_hz']:.0f} Hz; "
                    f"position loop PM {p['phase_margin_deg']:.1f} deg GM {p['gain_margin_db']:.2f} dB at "
                    f"{p['gain_margin_hz']:.0f} Hz; bandwidth {design['bandwidth_hz']:.1f} Hz"
                )
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--machine", action="append", help="a machine file (repeat); default: the three examples")
    main(parser.parse_args().machine or [str(m) for m in MACHINES])
