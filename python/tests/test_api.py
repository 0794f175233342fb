"""The scripting API: scenes, simulations, particles, bodies, errors, the GIL."""

import csv
import threading
import time

import numpy as np
import pytest

import regolith

SMALL = {"sph.spacing": 0.006, "simulation.end_time": 0.1}


def test_cone_scripted_in_python_matches_the_cli_bit_for_bit(cli, scenes, tmp_path):
    """The cone rig of cone_penetrometer.toml, run by the CLI, against the same push scripted
    from Python: place the cone as the rig does, prescribe its speed, step, read the force."""
    path = scenes / "cone_penetrometer.toml"
    sets = {"sph.spacing": 0.008, "simulation.end_time": 0.25}
    cli("run", path, *[a for k, v in sets.items() for a in ("--set", f"{k}={v}")], "--quiet", "--out", tmp_path / "cli")
    with open(tmp_path / "cli" / "series.csv") as f:
        rows = list(csv.DictReader(f))
    speed = 0.05  # rig.speed of the scene
    scene = regolith.load_scene(path, overrides=sets)
    scene.set_prescribed("cone", [0.0, 0.0, -speed])
    scene.place_on_soil("cone")
    sim = regolith.Simulation(scene)
    cone = sim.body("cone")
    end = scene.end_time
    forces, times = [], []
    while sim.time < end * (1 - 1e-12):
        sim.step(end - sim.time)
        times.append(sim.time)
        forces.append(cone.fsi_force[2])
    cli_force = [float(r["cone_force"]) for r in rows[1:]]
    cli_time = [float(r["time"]) for r in rows[1:]]
    assert len(forces) == len(cli_force) > 50
    assert times == cli_time
    assert forces == cli_force, "bit-identical on the CPU"
    assert max(forces) > 0.0, "the cone met the soil"


def test_particles_have_the_right_shapes_and_dtypes(scenes):
    sim = regolith.Simulation(regolith.load_scene(scenes / "cone_penetrometer.toml", overrides=SMALL))
    sim.step()
    p = sim.particles()
    n = sim.n_particles
    assert n > 1000
    assert p["x"].shape == (n, 3) and p["v"].shape == (n, 3) and p["stress"].shape == (n, 6)
    for k in ("p", "q", "p_c", "density", "specific_volume", "material", "phase", "id"):
        assert p[k].shape == (n,), k
    assert p["phase"].dtype == np.uint32 and not p["phase"].any(), "a dry scene holds soil only (phase 0)"
    assert p["x"].dtype == np.float32 and sim.precision == "f32"
    assert p["material"].dtype == np.uint32 and p["id"].dtype == np.uint32
    assert len(np.unique(p["id"])) == n
    # The bed is at rest under gravity: compression (p > 0) grows with depth.
    deep, shallow = p["x"][:, 2] < 0.02, p["x"][:, 2] > 0.05
    assert p["p"][deep].mean() > p["p"][shallow].mean() > -1.0
    assert np.allclose(p["density"], 1600.0, rtol=0.05)
    f64 = regolith.Simulation(
        regolith.load_scene(scenes / "cone_penetrometer.toml", overrides={**SMALL, "simulation.precision": "f64"})
    )
    assert f64.particles()["x"].dtype == np.float64


def test_bodies_move_as_told_and_feel_the_soil(scenes):
    scene = regolith.load_scene(scenes / "cone_probe.toml", overrides={"sph.spacing": 0.008})
    sim = regolith.Simulation(scene)
    cone = sim.body("cone")
    z0 = cone.position[2]
    cone.set_velocity([0.0, 0.0, -0.05])
    n = sim.advance(0.25)
    assert n >= 1 and sim.time == pytest.approx(0.25, abs=1e-9)
    assert cone.position[2] == pytest.approx(z0 - 0.05 * 0.25, abs=1e-5)
    assert cone.velocity[2] == pytest.approx(-0.05, rel=1e-6)
    assert cone.fsi_force[2] > 0.0, "the soil pushes the cone up"
    assert len(cone.rotation) == 4 and len(cone.fsi_torque) == 3
    with pytest.raises(regolith.InputError, match="no body named"):
        sim.body("wheel")
    with pytest.raises(regolith.InputError, match="not driven by a vehicle joint"):
        cone.set_motor_target(1.0)


def test_a_bad_override_raises_scene_error_with_the_cli_line(cli, scenes):
    path = scenes / "cone_penetrometer.toml"
    with pytest.raises(regolith.SceneError) as e:
        regolith.load_scene(path, overrides={"sph.spacing": -0.01})
    r = cli("check", path, "--set", "sph.spacing=-0.01", check=False)
    assert r.returncode == 2
    assert r.stderr.strip() == f"error: {e.value}"
    assert "sph.spacing" in str(e.value) and "\n" not in str(e.value)
    assert isinstance(e.value, regolith.InputError) and isinstance(e.value, regolith.RegolithError)
    with pytest.raises(regolith.InputError, match="not a TOML value"):
        regolith.load_scene(path, overrides={"sph.spacing": object()})
    with pytest.raises(regolith.SceneError, match="cannot read"):
        regolith.load_scene(path.with_name("missing.toml"))


def test_stepping_releases_the_gil(scenes):
    sim = regolith.Simulation(regolith.load_scene(scenes / "cone_penetrometer.toml", overrides=SMALL))
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=count)
    t0 = time.perf_counter()
    t.start()
    sim.advance(0.02)
    t1 = time.perf_counter()
    stop.set()
    t.join()
    during = [x for x in ticks if t0 < x < t1]
    assert t1 - t0 > 0.2, "long enough to tell"
    # With the GIL held the thread would not run at all until the call returned.
    assert len(during) > 20, f"{len(during)} ticks in {t1 - t0:.2f} s"


def test_reading_while_another_thread_steps_waits_without_deadlock(scenes):
    """A thread reads sim.time and a body's force while another advances the same simulation:
    the reader waits for the step with the GIL released (holding it would deadlock both: the
    stepper needs the GIL back to return). faulthandler turns a hang into a failure."""
    import faulthandler

    sim = regolith.Simulation(regolith.load_scene(scenes / "cone_penetrometer.toml", overrides=SMALL))
    cone = sim.body("cone")
    seen = []

    def stepper():
        for _ in range(5):
            sim.advance(0.002)

    faulthandler.dump_traceback_later(120, exit=True)
    try:
        t = threading.Thread(target=stepper)
        t.start()
        while t.is_alive():
            seen.append((sim.time, cone.fsi_force[2]))
        t.join()
    finally:
        faulthandler.cancel_dump_traceback_later()
    assert len(seen) > 0
    times = [s[0] for s in seen]
    assert times == sorted(times), "reads see whole steps, in order"
    assert sim.time >= 0.01 - 1e-9


def test_run_returns_the_summary(scenes, tmp_path):
    s = regolith.run(scenes / "cone_penetrometer.toml", tmp_path, overrides={"sph.spacing": 0.008, "simulation.end_time": 0.05})
    assert s["rig"]["type"] == "cone" and s["steps"] > 0 and not s["nan_detected"]
    assert (tmp_path / "summary.json").exists()
    with pytest.raises(regolith.InputError, match="apply overrides when loading"):
        regolith.run(regolith.load_scene(scenes / "cone_penetrometer.toml"), tmp_path, overrides={"a": 1})


def test_element_matches_the_closed_form(materials):
    """Drained triaxial on Drucker–Prager sand: q at failure against the Mohr–Coulomb closed
    form the element driver reports (the Rust tests check the path itself)."""
    e = regolith.element(materials / "sand_dp.toml", "drained-triaxial", 1e4, axial_strain=0.05, steps=500)
    assert isinstance(e["q"], np.ndarray) and e["q"].dtype == np.float64
    assert e["q"][-1] == pytest.approx(e["expected"]["failure_q"], rel=0.02)
    with pytest.raises(regolith.InputError, match="allowed: isotropic"):
        regolith.element(materials / "sand_dp.toml", "shear", 1e4, axial_strain=0.1)
    with pytest.raises(regolith.InputError, match="p_end: is required"):
        regolith.element(materials / "sand_dp.toml", "isotropic", 1e4)
