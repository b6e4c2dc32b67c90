"""Milling forces (mechanistic and Choi 1999's average model) on the workpiece, in real MuJoCo runs."""

import math

import mujoco
import numpy as np
import pytest
from scipy.integrate import quad

from twin.errors import TwinInputError
from twin.machines import build
from twin.machining.cutting import (
    AverageForce,
    EndMilling,
    ForceModels,
    immersion_angles,
    mean_tool_forces_N,
    step_tool_forces_N,
)
from twin.machining.materials import ALUMINIUM_7075_T6
from twin.scenario import run_scenario, scenario_from_dict

K = ALUMINIUM_7075_T6
RPM, FLUTES, D_MM = 6000.0, 2, 10.0
FEED_M_PER_S = 0.02  # 0.1 mm per tooth at 6000 rpm, 2 flutes
SETTLED_S = 0.2  # mean forces taken after this; 0.4 s = 80 whole tooth periods


def _feed(n_flutes, c_mm):
    """Every flute's chip vector when the tool feeds ``c_mm`` per tooth without vibration."""
    return np.full(n_flutes, c_mm), np.zeros(n_flutes)


def _slot_scenario(axial_mm=2.0, radial_mm=D_MM, mode="up", duration_s=0.6, **extra):
    """X feed at constant speed on linear_motor_xy, stiff PIDs with feedforward, cutter engaged."""
    cut = dict(
        type="end_milling",
        spindle_rpm=RPM,
        n_flutes=FLUTES,
        diameter_mm=D_MM,
        axial_depth_mm=axial_mm,
        radial_depth_mm=radial_mm,
        mode=mode,
        **extra,
    )
    return scenario_from_dict(
        dict(
            machine="linear_motor_xy",
            duration_s=duration_s,
            timestep_s=1e-4,
            control_period_s=5e-4,
            controllers={
                "x": dict(
                    type="pid", params=dict(kp=2e4, ki=2e5, kd=150, tf_s=5e-4), velocity_ff=1.97, acceleration_ff=0.533
                ),
                "y": dict(
                    type="pid", params=dict(kp=7e3, ki=7e4, kd=50, tf_s=5e-4), velocity_ff=0.367, acceleration_ff=0.173
                ),
            },
            reference=dict(type="ramp", rate_m_per_s=FEED_M_PER_S, axes=["x"]),
            disturbances=[cut],
        )
    )


def _mean_workpiece_force(result):
    return result.workpiece_force_N[result.t_s >= SETTLED_S].mean(axis=0)


def _expected_workpiece_force(axial_mm, radial_mm, mode):
    """Closed-form mean force on the tool, feed frame; the tool feeds along -x (the table moves
    +x), so feed = -x, normal = z x feed = -y: the workpiece gets (F_x, F_y, -F_z) in the world."""
    c_mm = FEED_M_PER_S * 1e3 / (FLUTES * RPM / 60.0)
    phi_st, phi_ex = immersion_angles(radial_mm, D_MM, mode)
    f = mean_tool_forces_N(
        K, n_flutes=FLUTES, axial_depth_mm=axial_mm, feed_per_tooth_mm=c_mm, phi_st=phi_st, phi_ex=phi_ex
    )
    return np.array([f[0], f[1], -f[2]])


def test_closed_form_mean_equals_integral_of_instantaneous_model():
    """Independent check: integrate the flute force F(phi) numerically (quad) over the immersion."""
    a, c = 3.0, 0.12
    for mode, ae in (("up", 3.0), ("down", 3.0), ("up", 10.0)):
        st, ex = immersion_angles(ae, D_MM, mode)

        def flute(phi, i):
            h = c * math.sin(phi)
            ft, fr, fa = a * (K.K_tc * h + K.K_te), a * (K.K_rc * h + K.K_re), a * (K.K_ac * h + K.K_ae)
            return (-ft * math.cos(phi) - fr * math.sin(phi), ft * math.sin(phi) - fr * math.cos(phi), fa)[i]

        numeric = [3 / (2 * math.pi) * quad(flute, st, ex, args=(i,))[0] for i in range(3)]
        np.testing.assert_allclose(
            mean_tool_forces_N(K, n_flutes=3, axial_depth_mm=a, feed_per_tooth_mm=c, phi_st=st, phi_ex=ex),
            numeric,
            rtol=1e-10,
        )


def test_step_average_carries_the_exact_impulse_over_a_revolution():
    st, ex = immersion_angles(4.0, D_MM, "down")
    n = 97  # a step that does not divide the revolution, with wrap-around past 2 pi
    step = 2 * math.pi / n
    forces = np.array(
        [step_tool_forces_N(K.as_array(), 3, 2.0, *_feed(3, 0.1), st, ex, 0.3 + i * step, step, 0.0) for i in range(n)]
    )
    np.testing.assert_allclose(
        forces.mean(axis=0),
        mean_tool_forces_N(K, n_flutes=3, axial_depth_mm=2.0, feed_per_tooth_mm=0.1, phi_st=st, phi_ex=ex),
        rtol=1e-12,
    )


def _helical_step_force_by_quadrature(a, c, st, ex, n_flutes, angle, step, lag, discs=400, angles=400):
    """The step-averaged force of helical flutes by brute force, from the force law itself: the
    depth cut into ``discs`` straight discs, each lagging its height's share of ``lag``, the step
    into ``angles`` sub-angles (midpoint rule in both)."""
    z = (np.arange(discs) + 0.5) / discs  # height / depth
    t = angle + (np.arange(angles) + 0.5) / angles * step
    phi = (t[:, None, None] - lag * z[None, :, None] - 2 * math.pi / n_flutes * np.arange(n_flutes)) % (2 * math.pi)
    on = (phi >= st) & (phi <= ex)
    h = c * np.sin(phi)
    da = a / discs
    ft, fr, fa = da * (K.K_tc * h + K.K_te), da * (K.K_rc * h + K.K_re), da * (K.K_ac * h + K.K_ae)
    fx = np.where(on, -ft * np.cos(phi) - fr * np.sin(phi), 0.0)
    fy = np.where(on, ft * np.sin(phi) - fr * np.cos(phi), 0.0)
    fz = np.where(on, fa, 0.0)
    return np.array([f.sum(axis=(1, 2)).mean() for f in (fx, fy, fz)])


@pytest.mark.parametrize(
    ("ae", "mode", "n_flutes", "angle", "step", "lag"),
    [
        (3.0, "up", 2, 0.2, 0.3, 0.7),  # the step crosses the entry, the edge spans it
        (3.0, "down", 3, 6.1, 0.4, 1.3),  # wraps past 2 pi
        (10.0, "up", 4, 1.0, 0.05, 2 * math.pi + 0.9),  # more than a whole turn of the edge
        (6.0, "down", 1, 3.0, 1.5, 0.2),  # a step longer than the lag
    ],
)
def test_helical_step_force_equals_brute_force_discs(ae, mode, n_flutes, angle, step, lag):
    st, ex = immersion_angles(ae, D_MM, mode)
    exact = step_tool_forces_N(K.as_array(), n_flutes, 4.0, *_feed(n_flutes, 0.1), st, ex, angle, step, lag)
    brute = _helical_step_force_by_quadrature(4.0, 0.1, st, ex, n_flutes, angle, step, lag)
    scale = np.abs(
        mean_tool_forces_N(K, n_flutes=n_flutes, axial_depth_mm=4.0, feed_per_tooth_mm=0.1, phi_st=0.0, phi_ex=math.pi)
    ).max()
    np.testing.assert_allclose(exact, brute, atol=2e-3 * scale)


def test_helix_of_one_pitch_in_a_slot_gives_the_constant_mean_force():
    """Altintas ch. 2.5: when the edge's lag over the depth is one flute pitch, every angle of a
    slot is cut at every instant by one disc: the force is constant, the mean of straight flutes."""
    for n_flutes in (2, 3, 4):
        mean = mean_tool_forces_N(
            K, n_flutes=n_flutes, axial_depth_mm=3.0, feed_per_tooth_mm=0.1, phi_st=0.0, phi_ex=math.pi
        )
        for angle in np.linspace(0.0, 2 * math.pi, 11):
            for lag in (2 * math.pi / n_flutes, 2 * math.pi + 2 * math.pi / n_flutes):
                force = step_tool_forces_N(
                    K.as_array(), n_flutes, 3.0, *_feed(n_flutes, 0.1), 0.0, math.pi, angle, 0.01, lag
                )
                np.testing.assert_allclose(force, mean, rtol=1e-9)


def test_helix_keeps_the_mean_and_cuts_the_peak():
    st, ex = immersion_angles(2.0, D_MM, "down")
    n = 360
    step = 2 * math.pi / n
    angles = 0.1 + step * np.arange(n)
    straight = np.array(
        [step_tool_forces_N(K.as_array(), 2, 3.0, *_feed(2, 0.1), st, ex, x, step, 0.0) for x in angles]
    )
    helical = np.array([step_tool_forces_N(K.as_array(), 2, 3.0, *_feed(2, 0.1), st, ex, x, step, 0.6) for x in angles])
    np.testing.assert_allclose(
        helical.mean(axis=0),
        mean_tool_forces_N(K, n_flutes=2, axial_depth_mm=3.0, feed_per_tooth_mm=0.1, phi_st=st, phi_ex=ex),
        rtol=1e-9,
    )
    assert np.abs(helical).max(axis=0)[1] < 0.8 * np.abs(straight).max(axis=0)[1]


def test_slot_mean_forces_match_closed_form_and_spectrum_peaks_at_tooth_frequency():
    res = run_scenario(_slot_scenario()).run
    mean = _mean_workpiece_force(res)
    expected = _expected_workpiece_force(2.0, D_MM, "up")
    np.testing.assert_allclose(mean, expected, rtol=0.02)
    assert abs(expected[1]) > 100.0  # a real load: ~112 N feed-normal in this slot

    # spectra over the settled part: force and tracking error peak at N rpm / 60 = 200 Hz
    sel = res.t_s >= SETTLED_S
    dt = res.control_period_s
    f = np.fft.rfftfreq(sel.sum(), dt)
    tooth_hz = FLUTES * RPM / 60.0
    fy = np.abs(np.fft.rfft(res.workpiece_force_N[sel, 1] - mean[1]))
    high = f > 50.0  # above the servo bandwidth
    peak = f[high][np.argmax(fy[high])]
    assert peak == pytest.approx(tooth_hz, abs=f[1])
    second = np.argmin(np.abs(f - 2 * tooth_hz))
    assert fy[second] > 10 * np.median(fy[high])  # the harmonic stands out too
    ey = np.abs(np.fft.rfft(res.error_m()[sel, 1]))
    assert f[high][np.argmax(ey[high])] == pytest.approx(tooth_hz, abs=f[1])


def test_doubling_axial_depth_doubles_mean_force():
    f1 = _mean_workpiece_force(run_scenario(_slot_scenario(axial_mm=1.5)).run)
    f2 = _mean_workpiece_force(run_scenario(_slot_scenario(axial_mm=3.0)).run)
    np.testing.assert_allclose(f2, 2 * f1, rtol=0.02)


def test_up_and_down_milling_mirror_the_force_signs():
    """At 10 % radial immersion both the feed and the feed-normal mean forces change sign."""
    up = _mean_workpiece_force(run_scenario(_slot_scenario(radial_mm=1.0, mode="up")).run)
    down = _mean_workpiece_force(run_scenario(_slot_scenario(radial_mm=1.0, mode="down")).run)
    np.testing.assert_allclose(up, _expected_workpiece_force(2.0, 1.0, "up"), rtol=0.02)
    np.testing.assert_allclose(down, _expected_workpiece_force(2.0, 1.0, "down"), rtol=0.02)
    assert np.sign(up[0]) == -np.sign(down[0])
    assert np.sign(up[1]) == -np.sign(down[1])


def test_cutting_force_is_off_outside_its_window():
    res = run_scenario(_slot_scenario(start_s=0.1, stop_s=0.3, duration_s=0.4)).run
    force = np.abs(res.workpiece_force_N).max(axis=1)
    assert force[res.t_s < 0.1 - 1e-9].max() == 0.0
    assert force[res.t_s >= 0.3].max() == 0.0
    assert force[(res.t_s > 0.15) & (res.t_s < 0.25)].min() > 10.0


def test_average_force_model_is_choi1999_eq_4_5():
    """F_x = k_il v_x - k_c v_y, F_y = k_il v_y + k_c v_x, checked against the run's velocities."""
    bm = build("linear_motor_xy")
    forces = ForceModels([AverageForce(-2500.0, 2500.0)], bm)
    data = mujoco.MjData(bm.model)
    data.qvel[bm.joint_dof_index("x_table")] = 0.03
    data.qvel[bm.joint_dof_index("y_table")] = -0.01
    np.testing.assert_allclose(
        forces.force_N(data.qpos, data.qvel, 0.0), [-2500 * 0.03 - 2500 * -0.01, -2500 * -0.01 + 2500 * 0.03, 0.0]
    )


def test_average_force_harmonic_fraction_bounded():
    with pytest.raises(TwinInputError, match="harmonic_fraction"):
        AverageForce(harmonic_fraction=0.25)
    with pytest.raises(TwinInputError, match="radial_depth_mm"):
        EndMilling(6000, 2, 10.0, 2.0, 12.0)
