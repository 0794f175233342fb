//! `regolith._regolith`: the compiled half of the Python package. The pure-Python half
//! (`python/regolith/`) re-exports it, turns JSON results into dicts and holds the Ray runner.
//!
//! Every Regolith error becomes a Python exception whose message is the one line the
//! command-line tool prints (without its `error: ` prefix). Stepping releases the GIL.

use pyo3::sync::MutexExt;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

use numpy::{PyArray1, PyArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use regolith::fsi::{Real, SphSolver};
use regolith::input::InputError as RInputError;
use regolith::run::{RunError as RRunError, RunOptions};
use regolith::scene::Scene as RScene;
use regolith::sim::Simulation as RSim;
use regolith::sweep;

create_exception!(_regolith, RegolithError, PyException, "Base class of every Regolith error.");
create_exception!(
    _regolith,
    InputError,
    RegolithError,
    "A wrong input: a file, a key, an argument; the message names it and what is allowed."
);
create_exception!(
    _regolith,
    SceneError,
    InputError,
    "A wrong scene file or override: the message names the file, the key and what is allowed."
);
create_exception!(_regolith, BuildError, RegolithError, "A scene that validated could not be built.");
create_exception!(_regolith, SolverError, RegolithError, "The soil solver stopped (non-finite state, runaway).");
create_exception!(_regolith, RunError, RegolithError, "A whole run failed or was stopped.");
create_exception!(_regolith, ElementError, RegolithError, "A material-point test failed.");

fn input_err(e: RInputError) -> PyErr {
    InputError::new_err(e.to_string())
}
fn scene_err(e: RInputError) -> PyErr {
    SceneError::new_err(e.to_string())
}
fn report(e: &(dyn std::error::Error + 'static)) -> String {
    regolith::error::report(e)
}
fn build_err(e: regolith::build::BuildError) -> PyErr {
    BuildError::new_err(report(&e))
}
fn solver_err(e: regolith::fsi::SolverError) -> PyErr {
    SolverError::new_err(report(&e))
}
fn run_err(e: RRunError) -> PyErr {
    match e {
        RRunError::Build(e) => build_err(e),
        e => RunError::new_err(report(&e)),
    }
}
fn arg_err(name: &str, message: impl std::fmt::Display) -> PyErr {
    InputError::new_err(format!("{name}: {message}"))
}

/// A Python value as a TOML value (bool, int, float, str, list/tuple, dict).
fn to_toml(key: &str, v: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return Ok(toml::Value::Integer(v.extract()?));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items: Vec<Bound<'_, PyAny>> = v.try_iter()?.collect::<PyResult<_>>()?;
        return Ok(toml::Value::Array(items.iter().map(|x| to_toml(key, x)).collect::<PyResult<_>>()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut t = toml::Table::new();
        for (k, x) in d.iter() {
            t.insert(k.extract::<String>()?, to_toml(key, &x)?);
        }
        return Ok(toml::Value::Table(t));
    }
    // numpy scalars and other numbers.
    if let Ok(f) = v.extract::<f64>() {
        return Ok(toml::Value::Float(f));
    }
    Err(arg_err(
        &format!("overrides[{key:?}]"),
        format!("{} is not a TOML value (allowed: bool, int, float, str, list, dict)", v.get_type().name()?),
    ))
}

fn overrides_list(overrides: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<(String, toml::Value)>> {
    let mut sets = Vec::new();
    if let Some(d) = overrides {
        for (k, v) in d.iter() {
            let key: String = k.extract().map_err(|_| arg_err("overrides", "keys must be dotted scene keys (str)"))?;
            let value = to_toml(&key, &v)?;
            sets.push((key, value));
        }
    }
    Ok(sets)
}

/// A validated scene, ready to build.
#[pyclass(module = "regolith._regolith", name = "Scene", from_py_object)]
#[derive(Clone)]
struct Scene {
    inner: RScene,
}

#[pymethods]
impl Scene {
    /// The scene file.
    #[getter]
    fn path(&self) -> PathBuf {
        self.inner.path.clone()
    }
    /// End time (s).
    #[getter]
    fn end_time(&self) -> f64 {
        self.inner.end_time
    }
    /// Particle spacing d0 (m).
    #[getter]
    fn spacing(&self) -> f64 {
        self.inner.solver.spacing
    }
    /// Exchange interval between soil and bodies (s): what one `Simulation.step()` advances.
    #[getter]
    fn exchange_interval(&self) -> f64 {
        self.inner.exchange_interval
    }
    /// `"f32"` or `"f64"`.
    #[getter]
    fn precision(&self) -> &'static str {
        match self.inner.precision {
            regolith::scene::Precision::F32 => "f32",
            regolith::scene::Precision::F64 => "f64",
        }
    }
    /// The bodies' names, in scene order (vehicle links included).
    #[getter]
    fn bodies(&self) -> Vec<String> {
        self.inner.bodies.iter().map(|b| b.desc.name.clone()).collect()
    }
    /// Moves body `name` vertically so that its lowest point sits one spacing above the top
    /// soil particle under it, as the rigs place their bodies; returns that height (m), the
    /// rigs' zero of depth plus half a spacing.
    fn place_on_soil(&mut self, name: &str) -> PyResult<f64> {
        let i = self.index(name)?;
        regolith::rig::place_on_soil(&mut self.inner, i).map_err(build_err)
    }
    /// Makes body `name` move at a prescribed velocity (m/s, rad/s) from the start, as the
    /// rigs do with the body they drive (`Body.set_velocity` changes it while stepping).
    #[pyo3(signature = (name, linear, angular = [0.0; 3]))]
    fn set_prescribed(&mut self, name: &str, linear: [f64; 3], angular: [f64; 3]) -> PyResult<()> {
        if !linear.iter().chain(&angular).all(|x| x.is_finite()) {
            return Err(arg_err("set_prescribed", "velocities must be finite"));
        }
        let i = self.index(name)?;
        self.inner.bodies[i].desc.motion = regolith::rigid::Motion::Prescribed { linvel: linear, angvel: angular };
        Ok(())
    }
    /// Height (m) of the highest soil particle's centre within `r` of `(x, y)` in the scene's
    /// initial terrain.
    fn soil_top(&self, x: f64, y: f64, r: f64) -> PyResult<f64> {
        regolith::rig::soil_top(&self.inner, x, y, r).map_err(build_err)
    }
    /// What `regolith check` prints about the scene.
    fn describe(&self) -> String {
        regolith::scene::describe(&self.inner)
    }
    fn __repr__(&self) -> String {
        format!(
            "Scene({:?}, d0 = {} m, end_time = {} s, {} bodies)",
            self.inner.path.display().to_string(),
            self.inner.solver.spacing,
            self.inner.end_time,
            self.inner.bodies.len()
        )
    }
}

impl Scene {
    fn index(&self, name: &str) -> PyResult<usize> {
        self.inner.bodies.iter().position(|b| b.desc.name == name).ok_or_else(|| {
            let names: Vec<&str> = self.inner.bodies.iter().map(|b| b.desc.name.as_str()).collect();
            arg_err("body", format!("no body named {name:?} (bodies: {})", names.join(", ")))
        })
    }
}

/// Loads and validates a scene file; `overrides` maps dotted keys to values, as `--set`.
#[pyfunction]
#[pyo3(signature = (path, overrides = None))]
fn load_scene(path: PathBuf, overrides: Option<&Bound<'_, PyDict>>) -> PyResult<Scene> {
    let sets = overrides_list(overrides)?;
    let mut inner = regolith::scene::load_scene(&path, &sets).map_err(scene_err)?;
    regolith::build::backend::resolve_backend(&mut inner).map_err(|m| scene_err(RInputError::file(&path, m)))?;
    Ok(Scene { inner })
}

/// The two precisions a simulation runs in.
enum Any {
    F32(RSim<f32>),
    F64(RSim<f64>),
}

macro_rules! with {
    ($any:expr, $s:ident => $e:expr) => {
        match $any {
            Any::F32($s) => $e,
            Any::F64($s) => $e,
        }
    };
}

/// A scene being simulated, stepped from Python.
#[pyclass(module = "regolith._regolith", name = "Simulation")]
struct Simulation {
    inner: Mutex<Any>,
    names: Vec<String>,
}

fn report_dict<'py>(py: Python<'py>, r: &regolith::coupling::ExchangeReport) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("time", r.time)?;
    d.set_item("fluid_steps", r.fluid_steps)?;
    d.set_item("rigid_steps", r.rigid_steps)?;
    d.set_item("max_speed", r.max_speed)?;
    d.set_item("pairs", r.pairs)?;
    d.set_item("rarefied_max", r.rarefied_max)?;
    d.set_item("dt_min", r.dt_min)?;
    d.set_item("dt_max", r.dt_max)?;
    Ok(d)
}

fn particles_of<'py, T: Real + numpy::Element>(py: Python<'py>, s: &RSim<T>) -> PyResult<Bound<'py, PyDict>> {
    let f: &dyn SphSolver<T> = s.system.fluid.as_ref();
    let n = f.active();
    let vec3 = |xs: &[regolith::fsi::math::Vec3<T>]| -> PyResult<Bound<'py, PyAny>> {
        let flat: Vec<T> = xs[..n].iter().flat_map(|v| [v.x, v.y, v.z]).collect();
        Ok(PyArray1::from_vec(py, flat).reshape([n, 3])?.into_any())
    };
    let st = &f.stresses()[..n];
    let d = PyDict::new(py);
    d.set_item("x", vec3(f.positions())?)?;
    d.set_item("v", vec3(f.velocities())?)?;
    d.set_item("p", PyArray1::from_vec(py, st.iter().map(|s| s.pressure()).collect()))?;
    d.set_item("q", PyArray1::from_vec(py, st.iter().map(|s| s.von_mises()).collect()))?;
    let six: Vec<T> = st.iter().flat_map(|s| [s.xx, s.yy, s.zz, s.xy, s.xz, s.yz]).collect();
    d.set_item("stress", PyArray1::from_vec(py, six).reshape([n, 6])?)?;
    d.set_item("p_c", PyArray1::from_vec(py, f.states()[..n].iter().map(|s| s.pc).collect()))?;
    d.set_item("specific_volume", PyArray1::from_vec(py, f.states()[..n].iter().map(|s| s.v).collect()))?;
    d.set_item("density", PyArray1::from_vec(py, f.densities()[..n].to_vec()))?;
    d.set_item("material", PyArray1::from_vec(py, f.material_ids()[..n].iter().map(|m| u32::from(*m)).collect()))?;
    let mats = f.materials();
    let phase: Vec<u32> = f.material_ids()[..n].iter().map(|m| u32::from(mats[*m as usize].is_water())).collect();
    d.set_item("phase", PyArray1::from_vec(py, phase))?;
    d.set_item("id", PyArray1::from_vec(py, f.ids()[..n].to_vec()))?;
    Ok(d)
}

impl Simulation {
    /// The simulation, waiting for it with the GIL released: a thread stepping holds the lock
    /// with the GIL released and needs the GIL back to return, so a reader waiting on the lock
    /// with the GIL held would deadlock both.
    fn lock(&self, py: Python<'_>) -> PyResult<MutexGuard<'_, Any>> {
        self.inner
            .lock_py_attached(py)
            .map_err(|_| SolverError::new_err("the simulation was poisoned by a panic in another thread"))
    }
    fn index(&self, name: &str) -> PyResult<usize> {
        self.names
            .iter()
            .position(|n| n == name)
            .ok_or_else(|| arg_err("body", format!("no body named {name:?} (bodies: {})", self.names.join(", "))))
    }
}

#[pymethods]
impl Simulation {
    /// Builds a scene (a `Scene` from `load_scene`, or a path).
    #[new]
    fn new(py: Python<'_>, scene: &Bound<'_, PyAny>) -> PyResult<Self> {
        let scene: RScene = match scene.extract::<Scene>() {
            Ok(s) => s.inner,
            Err(_) => {
                let path: PathBuf = scene.extract().map_err(|_| arg_err("scene", "must be a Scene or a path"))?;
                load_scene(path, None)?.inner
            }
        };
        let names = scene.bodies.iter().map(|b| b.desc.name.clone()).collect();
        let any = py
            .detach(|| match scene.precision {
                regolith::scene::Precision::F32 => RSim::<f32>::new(&scene).map(Any::F32),
                regolith::scene::Precision::F64 => RSim::<f64>::new(&scene).map(Any::F64),
            })
            .map_err(build_err)?;
        Ok(Self { inner: Mutex::new(any), names })
    }

    /// Simulated time (s).
    #[getter]
    fn time(&self, py: Python<'_>) -> PyResult<f64> {
        Ok(with!(&*self.lock(py)?, s => s.time()))
    }

    /// `"f32"` or `"f64"`.
    #[getter]
    fn precision(&self, py: Python<'_>) -> PyResult<&'static str> {
        Ok(match &*self.lock(py)? {
            Any::F32(_) => "f32",
            Any::F64(_) => "f64",
        })
    }

    /// Soil particles in the domain.
    #[getter]
    fn n_particles(&self, py: Python<'_>) -> PyResult<usize> {
        Ok(with!(&*self.lock(py)?, s => s.system.fluid.active()))
    }

    /// Advances one exchange interval, or `max` seconds if that is sooner; returns what the
    /// step did (time, fluid_steps, rigid_steps, max_speed, pairs, rarefied_max, dt_min,
    /// dt_max). Releases the GIL.
    #[pyo3(signature = (max = None))]
    fn step<'py>(&self, py: Python<'py>, max: Option<f64>) -> PyResult<Bound<'py, PyDict>> {
        if let Some(m) = max
            && !(m.is_finite() && m > 0.0)
        {
            return Err(arg_err("max", format!("must be a finite number of seconds > 0 (got {m})")));
        }
        let mut g = self.lock(py)?;
        let any: &mut Any = &mut g;
        let r = py.detach(|| with!(any, s => s.step_max(max))).map_err(solver_err)?;
        report_dict(py, &r)
    }

    /// Advances `duration` seconds of simulated time (the last exchange shortened to land on
    /// it); returns the number of exchanges. Releases the GIL.
    fn advance(&self, py: Python<'_>, duration: f64) -> PyResult<usize> {
        if !(duration.is_finite() && duration >= 0.0) {
            return Err(arg_err("duration", format!("must be a finite number of seconds >= 0 (got {duration})")));
        }
        let mut g = self.lock(py)?;
        let any: &mut Any = &mut g;
        py.detach(|| {
            with!(any, s => {
                let end = s.time() + duration;
                let mut n = 0;
                while end - s.time() > 1e-12 * end.abs().max(1.0) {
                    s.step_max(Some(end - s.time()))?;
                    n += 1;
                }
                Ok(n)
            })
        })
        .map_err(solver_err)
    }

    /// The soil particles in the domain as numpy arrays in the run's precision: `x`, `v`
    /// (n × 3, m and m/s), `p`, `q` (Pa), `stress` (n × 6: xx, yy, zz, xy, xz, yz, Pa, tension
    /// positive), `p_c` (Pa), `specific_volume`, `density` (kg/m³), `material`, `phase` (0
    /// soil, 1 water) and `id` (uint32). One copy of the solver's arrays, handed to numpy without a second. Not a
    /// zero-copy view on purpose: the solver reorders its particle arrays when it sorts them
    /// into cells and rewrites them while stepping with the GIL released, so a view would
    /// change, or tear, under the reader; `id` follows a particle from one call to the next.
    fn particles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        match &*self.lock(py)? {
            Any::F32(s) => particles_of(py, s),
            Any::F64(s) => particles_of(py, s),
        }
    }

    /// A body by name.
    fn body(slf: &Bound<'_, Self>, name: &str) -> PyResult<Body> {
        let index = slf.borrow().index(name)?;
        Ok(Body { sim: slf.clone().unbind(), index, name: name.to_string() })
    }

    /// The bodies' names, in scene order.
    #[getter]
    fn bodies(&self) -> Vec<String> {
        self.names.clone()
    }

    /// Sets the target speed (rad/s or m/s) of the motor of joint `joint` of vehicle `vehicle`.
    fn set_motor_target(&self, py: Python<'_>, vehicle: &str, joint: &str, target: f64) -> PyResult<()> {
        if !target.is_finite() {
            return Err(arg_err("target", format!("must be finite (got {target})")));
        }
        let mut g = self.lock(py)?;
        with!(&mut *g, s => {
            let j = s.vehicle_joint(vehicle, joint).ok_or_else(|| {
                arg_err("joint", format!("vehicle {vehicle:?} has no built joint {joint:?}"))
            })?;
            s.set_motor_target(j, target);
        });
        Ok(())
    }

    /// Drives vehicle `vehicle` at constant wheel speeds (rad/s, forward positive): left-side
    /// wheels at `left`, right-side ones at `right`, torques up to `max_torque` (N m).
    fn set_vehicle_drive(&self, py: Python<'_>, vehicle: &str, left: f64, right: f64, max_torque: f64) -> PyResult<()> {
        let mut g = self.lock(py)?;
        with!(&mut *g, s => s.set_vehicle_drive(vehicle, left, right, max_torque)).map_err(build_err)
    }

    /// Kinetic energy of the soil in the domain (J).
    fn soil_kinetic_energy(&self, py: Python<'_>) -> PyResult<f64> {
        Ok(with!(&*self.lock(py)?, s => s.soil_kinetic_energy()))
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let g = self.lock(py)?;
        Ok(with!(&*g, s => format!(
            "Simulation(t = {:.6} s, {} particles, bodies: {})",
            s.time(),
            s.system.fluid.active(),
            self.names.join(", ")
        )))
    }
}

/// A body of a `Simulation`.
#[pyclass(module = "regolith._regolith", name = "Body")]
struct Body {
    sim: Py<Simulation>,
    index: usize,
    name: String,
}

impl Body {
    fn read<R>(&self, py: Python<'_>, f: impl FnOnce(&Any, regolith::sim::Body) -> R) -> PyResult<R> {
        let sim = self.sim.borrow(py);
        let g = sim.lock(py)?;
        let b = with!(&*g, s => s.bodies().nth(self.index));
        let b = b.ok_or_else(|| arg_err("body", "no longer in the simulation"))?;
        Ok(f(&g, b))
    }
    fn state(&self, py: Python<'_>) -> PyResult<regolith::body::BodyState> {
        self.read(py, |a, b| with!(a, s => s.body_state(b)))
    }
}

#[pymethods]
impl Body {
    /// Its name.
    #[getter]
    fn name(&self) -> String {
        self.name.clone()
    }
    /// Body-frame origin (m).
    #[getter]
    fn position(&self, py: Python<'_>) -> PyResult<[f64; 3]> {
        Ok(self.state(py)?.origin)
    }
    /// Orientation, unit quaternion `[x, y, z, w]`.
    #[getter]
    fn rotation(&self, py: Python<'_>) -> PyResult<[f64; 4]> {
        Ok(self.state(py)?.rotation)
    }
    /// Centre-of-mass velocity (m/s).
    #[getter]
    fn velocity(&self, py: Python<'_>) -> PyResult<[f64; 3]> {
        Ok(self.state(py)?.linvel)
    }
    /// Angular velocity (rad/s).
    #[getter]
    fn angular_velocity(&self, py: Python<'_>) -> PyResult<[f64; 3]> {
        Ok(self.state(py)?.angvel)
    }
    /// Mean soil force on the body over the last exchange interval (N).
    #[getter]
    fn fsi_force(&self, py: Python<'_>) -> PyResult<[f64; 3]> {
        self.read(py, |a, b| with!(a, s => s.fsi_wrench(b).force))
    }
    /// Mean soil torque about the centre of mass over the last exchange interval (N m).
    #[getter]
    fn fsi_torque(&self, py: Python<'_>) -> PyResult<[f64; 3]> {
        self.read(py, |a, b| with!(a, s => s.fsi_wrench(b).torque))
    }
    /// Sets a prescribed body's velocity (m/s, rad/s) from the next step on.
    #[pyo3(signature = (linear, angular = [0.0; 3]))]
    fn set_velocity(&self, py: Python<'_>, linear: [f64; 3], angular: [f64; 3]) -> PyResult<()> {
        if !linear.iter().chain(&angular).all(|x| x.is_finite()) {
            return Err(arg_err("set_velocity", "velocities must be finite"));
        }
        let sim = self.sim.borrow(py);
        let mut g = sim.lock(py)?;
        let b = with!(&*g, s => s.bodies().nth(self.index)).ok_or_else(|| arg_err("body", "not found"))?;
        with!(&mut *g, s => s.set_body_velocity(b, linear, angular));
        Ok(())
    }
    /// Sets the target speed of the motor driving this body (a vehicle link: the joint whose
    /// child it is).
    fn set_motor_target(&self, py: Python<'_>, target: f64) -> PyResult<()> {
        if !target.is_finite() {
            return Err(arg_err("target", format!("must be finite (got {target})")));
        }
        let sim = self.sim.borrow(py);
        let mut g = sim.lock(py)?;
        with!(&mut *g, s => {
            let joint = s.scene.vehicles.iter().find_map(|v| {
                v.model
                    .joints
                    .iter()
                    .find(|j| v.body(j.child) == self.index)
                    .map(|j| (v.name.clone(), j.name.clone()))
            });
            let (vehicle, joint) = joint.ok_or_else(|| {
                arg_err("set_motor_target", format!("body {:?} is not driven by a vehicle joint", self.name))
            })?;
            let j = s
                .vehicle_joint(&vehicle, &joint)
                .ok_or_else(|| arg_err("set_motor_target", format!("joint {joint:?} of {vehicle:?} was not built")))?;
            s.set_motor_target(j, target);
        });
        Ok(())
    }
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let st = self.state(py)?;
        Ok(format!("Body({:?}, position = {:?})", self.name, st.origin))
    }
}

/// Runs a scene end to end as `regolith run` does and returns `summary.json` as a JSON string.
/// Releases the GIL.
#[pyfunction]
#[pyo3(signature = (scene, out, overrides = None))]
fn run_json(
    py: Python<'_>,
    scene: &Bound<'_, PyAny>,
    out: PathBuf,
    overrides: Option<&Bound<'_, PyDict>>,
) -> PyResult<String> {
    let scene = match scene.extract::<Scene>() {
        Ok(s) if overrides.is_none() => s.inner,
        Ok(_) => {
            return Err(arg_err("overrides", "apply overrides when loading the scene: load_scene(path, overrides)"));
        }
        Err(_) => {
            let path: PathBuf = scene.extract().map_err(|_| arg_err("scene", "must be a Scene or a path"))?;
            load_scene(path, overrides)?.inner
        }
    };
    let summary = py.detach(|| regolith::run::run_scene(&scene, &RunOptions::quiet(&out))).map_err(run_err)?;
    serde_json::to_string(&summary).map_err(|e| RunError::new_err(e.to_string()))
}

/// A material-point test (`regolith element`); returns `element.json` as a JSON string.
#[pyfunction]
#[pyo3(signature = (material, test, p0, *, ocr = None, axial_strain = None, p_end = None, p_unload = None, steps = 2000, precision = "f64"))]
#[allow(clippy::too_many_arguments)]
fn element_json(
    material: PathBuf,
    test: &str,
    p0: f64,
    ocr: Option<f64>,
    axial_strain: Option<f64>,
    p_end: Option<f64>,
    p_unload: Option<f64>,
    steps: usize,
    precision: &str,
) -> PyResult<String> {
    use regolith::element::{Control, ElementError as EE, ElementSpec, ElementTest, run_element};
    let t = ElementTest::parse(test).ok_or_else(|| {
        arg_err("test", format!("{test:?} (allowed: isotropic, drained-triaxial, undrained-triaxial, oedometer)"))
    })?;
    let control = match (axial_strain, p_end) {
        (Some(e), None) => Control::AxialStrain(e),
        (None, Some(end)) => Control::Pressure { end, unload: p_unload },
        (Some(_), Some(_)) => return Err(arg_err("axial_strain", "give axial_strain or p_end, not both")),
        (None, None) => {
            let need = if t == ElementTest::Isotropic { "p_end" } else { "axial_strain" };
            return Err(arg_err(need, format!("is required for a {} test", t.name())));
        }
    };
    if p_unload.is_some() && p_end.is_none() {
        return Err(arg_err("p_unload", "needs p_end"));
    }
    let spec = ElementSpec { test: t, p0, ocr, control, steps };
    let params = regolith::material::load_material_file(&material).map_err(input_err)?;
    let map = |e: EE| match e {
        EE::Spec { flag, message } => arg_err(flag.trim_start_matches("--").replace('-', "_").as_str(), message),
        other => ElementError::new_err(report(&other)),
    };
    let json =
        |p: &regolith::element::ElementPath| serde_json::to_string(p).map_err(|e| ElementError::new_err(e.to_string()));
    match precision {
        "f64" => {
            let m = regolith::material::build_material::<f64>(&params, &material, "", "").map_err(input_err)?;
            json(&run_element(&m, &spec).map_err(map)?)
        }
        "f32" => {
            let m = regolith::material::build_material::<f32>(&params, &material, "", "").map_err(input_err)?;
            json(&run_element(&m, &spec).map_err(map)?)
        }
        p => Err(arg_err("precision", format!("{p:?} (allowed: \"f32\", \"f64\")"))),
    }
}

fn plan_of(
    scene: &Path,
    sets: &[String],
    vary: &[String],
    design: &str,
    samples: Option<usize>,
    seed: u64,
) -> PyResult<sweep::Plan> {
    let sets = sets
        .iter()
        .map(|s| regolith::scene::parse_set(s).map_err(|m| arg_err("sets", m)))
        .collect::<PyResult<Vec<_>>>()?;
    let vary = vary.iter().map(|v| sweep::parse_vary(v).map_err(input_err)).collect::<PyResult<Vec<_>>>()?;
    let design = match (design, samples) {
        ("grid", None) => sweep::Design::Grid,
        ("grid", Some(_)) => return Err(arg_err("samples", "applies to design=\"lhs\" only")),
        ("lhs", Some(samples)) => sweep::Design::Lhs { samples, seed },
        ("lhs", None) => return Err(arg_err("samples", "is required for design=\"lhs\"")),
        (d, _) => return Err(arg_err("design", format!("{d:?} (allowed: \"grid\", \"lhs\")"))),
    };
    sweep::Plan::new(scene, &sets, &vary, design).map_err(input_err)
}

fn shard_of(shard: Option<&str>) -> PyResult<Option<sweep::Shard>> {
    shard.map(|s| sweep::Shard::parse(s).map_err(input_err)).transpose()
}

/// The points of a sweep as a JSON list of `{point, id, overrides}`.
#[pyfunction]
#[pyo3(signature = (scene, sets, vary, design = "grid", samples = None, seed = 0))]
fn sweep_plan_json(
    scene: PathBuf,
    sets: Vec<String>,
    vary: Vec<String>,
    design: &str,
    samples: Option<usize>,
    seed: u64,
) -> PyResult<String> {
    let plan = plan_of(&scene, &sets, &vary, design, samples, seed)?;
    let points: Vec<serde_json::Value> = plan
        .points
        .iter()
        .map(|p| {
            serde_json::json!({
                "point": p.index,
                "id": p.id,
                "overrides": p.overrides.iter().map(|(k, v)| (k.clone(), sweep::toml_to_json(v))).collect::<serde_json::Map<_, _>>(),
            })
        })
        .collect();
    Ok(serde_json::Value::from(points).to_string())
}

/// The positions of the points of `shard` still to run in sweep directory `out`.
#[pyfunction]
#[pyo3(signature = (scene, sets, vary, design, samples, seed, out, shard = None, retry_failed = false))]
#[allow(clippy::too_many_arguments)]
fn sweep_pending(
    scene: PathBuf,
    sets: Vec<String>,
    vary: Vec<String>,
    design: &str,
    samples: Option<usize>,
    seed: u64,
    out: PathBuf,
    shard: Option<&str>,
    retry_failed: bool,
) -> PyResult<Vec<usize>> {
    let plan = plan_of(&scene, &sets, &vary, design, samples, seed)?;
    let done = sweep::read_all(&out).map_err(input_err)?;
    Ok(plan.pending(shard_of(shard)?, &done, retry_failed).iter().map(|p| p.index).collect())
}

/// Runs point `point` of a sweep (outputs under `out/points/<id>/`); returns its record as a
/// JSON line. Never raises for a failed point: the record says it failed, and why. Releases
/// the GIL.
#[pyfunction]
#[pyo3(signature = (scene, sets, vary, design, samples, seed, point, out))]
#[allow(clippy::too_many_arguments)]
fn sweep_run_point(
    py: Python<'_>,
    scene: PathBuf,
    sets: Vec<String>,
    vary: Vec<String>,
    design: &str,
    samples: Option<usize>,
    seed: u64,
    point: usize,
    out: PathBuf,
) -> PyResult<String> {
    let plan = plan_of(&scene, &sets, &vary, design, samples, seed)?;
    let p = plan
        .points
        .get(point)
        .ok_or_else(|| arg_err("point", format!("{point} (the sweep has {})", plan.points.len())))?;
    let rec = py.detach(|| plan.run_point(p, &out));
    serde_json::to_string(&rec).map_err(|e| RunError::new_err(e.to_string()))
}

/// Appends a record (a JSON line from `sweep_run_point`) to the results file of `shard`.
#[pyfunction]
#[pyo3(signature = (out, record, shard = None))]
fn sweep_append(out: PathBuf, record: &str, shard: Option<&str>) -> PyResult<()> {
    let r: sweep::Record = serde_json::from_str(record).map_err(|e| arg_err("record", e))?;
    std::fs::create_dir_all(&out).map_err(|e| input_err(RInputError::file(&out, format!("cannot create: {e}"))))?;
    sweep::append(&sweep::results_file(&out, shard_of(shard)?), &r).map_err(input_err)
}

/// Every record of a sweep directory (shards included), last per point id, as JSON lines.
#[pyfunction]
fn sweep_records_json(out: PathBuf) -> PyResult<Vec<String>> {
    let rs = sweep::read_all(&out).map_err(input_err)?;
    rs.iter().map(|r| serde_json::to_string(r).map_err(|e| RunError::new_err(e.to_string()))).collect()
}

/// Writes `results.csv` from the directory's records (shards are joined by `sweep_merge`).
#[pyfunction]
fn sweep_write_csv(out: PathBuf) -> PyResult<()> {
    let rs = sweep::read_all(&out).map_err(input_err)?;
    sweep::write_csv(&out, &rs).map_err(input_err)
}

/// Joins a sweep directory's shard files into `results.jsonl` and `results.csv`; returns the
/// number of points.
#[pyfunction]
fn sweep_merge(out: PathBuf) -> PyResult<usize> {
    sweep::merge(&out).map_err(input_err)
}

/// The ladders of a sweep over the resolution key `over` for the summary value `metric`
/// (see `regolith sweep converge`), as JSON.
#[pyfunction]
fn sweep_converge_json(out: PathBuf, over: &str, metric: &str) -> PyResult<String> {
    let ls = sweep::converge(&out, over, metric).map_err(input_err)?;
    serde_json::to_string(&ls).map_err(|e| RunError::new_err(e.to_string()))
}

/// The shard of a SLURM array task (`"i/n"`), from its environment, or None outside one.
#[pyfunction]
fn slurm_shard() -> PyResult<Option<String>> {
    Ok(sweep::Shard::from_slurm(|k| std::env::var(k).ok())
        .map_err(input_err)?
        .map(|s| format!("{}/{}", s.index, s.count)))
}

/// A batch failure as a Python exception: a wrong input is `InputError`, anything else
/// (a case failing its bounds, a run not carried out) `RunError`; one line either way.
fn batch_err(f: regolith::cli::Failure) -> PyErr {
    let line = regolith::cli::batch::failure_line(&f);
    match f {
        regolith::cli::Failure::Input(_) => InputError::new_err(line),
        _ => RunError::new_err(line),
    }
}

/// The runs of a batch named by its command line (`["study", "stability", ...]` or
/// `["calibrate", "triaxial", ...]`, as after `regolith`), as JSON: `what`, `out` and `runs`
/// (`index`, `id`, `label`, and `folder`, whose results file its record goes to).
#[pyfunction]
fn batch_runs_json(args: Vec<String>) -> PyResult<String> {
    let b = regolith::cli::batch::open(&args).map_err(batch_err)?;
    let runs: Vec<serde_json::Value> = b
        .runs()
        .into_iter()
        .map(|(index, id, label, folder)| {
            serde_json::json!({ "index": index, "id": id, "label": label, "folder": folder.display().to_string() })
        })
        .collect();
    let doc = serde_json::json!({ "what": b.what(), "out": b.out().display().to_string(), "runs": runs });
    Ok(doc.to_string())
}

/// The indices of the batch's runs to do: all (its records forgotten first) unless `resume`.
#[pyfunction]
fn batch_pending(args: Vec<String>, resume: bool, retry_failed: bool) -> PyResult<Vec<usize>> {
    let b = regolith::cli::batch::open(&args).map_err(batch_err)?;
    b.pending(resume, retry_failed).map_err(batch_err)
}

/// Runs run `index` of the batch (the GIL released) and returns its record as a JSON line.
#[pyfunction]
fn batch_run(py: Python<'_>, args: Vec<String>, index: usize) -> PyResult<String> {
    let b = regolith::cli::batch::open(&args).map_err(batch_err)?;
    let rec = py.detach(|| b.run(index)).map_err(batch_err)?;
    serde_json::to_string(&rec).map_err(|e| RunError::new_err(e.to_string()))
}

/// Writes the batch's tables from its records and returns the text the CLI prints; raises
/// `RunError` when a case fails its bounds or a run was not carried out.
#[pyfunction]
fn batch_finish(py: Python<'_>, args: Vec<String>) -> PyResult<String> {
    let b = regolith::cli::batch::open(&args).map_err(batch_err)?;
    py.detach(|| b.finish()).map_err(batch_err)
}

/// Regolith's version.
#[pyfunction]
fn version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

#[pymodule]
fn _regolith(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("RegolithError", py.get_type::<RegolithError>())?;
    m.add("InputError", py.get_type::<InputError>())?;
    m.add("BuildError", py.get_type::<BuildError>())?;
    m.add("SolverError", py.get_type::<SolverError>())?;
    m.add("RunError", py.get_type::<RunError>())?;
    m.add("ElementError", py.get_type::<ElementError>())?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add_class::<Scene>()?;
    m.add_class::<Simulation>()?;
    m.add_class::<Body>()?;
    m.add_function(wrap_pyfunction!(load_scene, m)?)?;
    m.add_function(wrap_pyfunction!(run_json, m)?)?;
    m.add_function(wrap_pyfunction!(element_json, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_plan_json, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_pending, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_run_point, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_append, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_records_json, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_write_csv, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_merge, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_converge_json, m)?)?;
    m.add_function(wrap_pyfunction!(slurm_shard, m)?)?;
    m.add_function(wrap_pyfunction!(batch_runs_json, m)?)?;
    m.add_function(wrap_pyfunction!(batch_pending, m)?)?;
    m.add_function(wrap_pyfunction!(batch_run, m)?)?;
    m.add_function(wrap_pyfunction!(batch_finish, m)?)?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    Ok(())
}
