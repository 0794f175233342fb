//! `recording.mcap`: what a run looked like, for Foxglove and the `mcap` readers.
//!
//! Topics (JSON message encoding, JSON schemas embedded in the file, zstd chunks):
//!
//! | topic | schema | when |
//! |---|---|---|
//! | `/terrain/particles` | `foxglove.PointCloud` (x, y, z, p, q, pc, speed as float32; material, and phase 0 soil / 1 water, as uint32) | every frame, unless `output.particles = false` |
//! | `/tf` | `foxglove.FrameTransforms`, each body under `world`, and each URDF link lumped into a vehicle link (sensor frames, mounts) under that link | every frame, when the scene has bodies |
//! | `/bodies/shapes` | `foxglove.SceneUpdate`, each body's geometry locked to its frame | at the start of each run (a rig run may change a shape) |
//! | `/bodies/wrench` | `regolith.BodyWrenches` | every frame, when the scene has bodies |
//! | `/rig/<type>` | `regolith.Rig.<type>` (slip, sinkage, drawbar pull, cone index, …) | every frame of a rig run |
//! | `/vehicles/<name>` | `regolith.Vehicle` (pose, speed, each wheel's slip, sinkage, spin) | every frame, per URDF vehicle |
//!
//! Frames are taken at t = 0 and then at the first exchange at or after each multiple of
//! `output.every`, so a run of length T has ⌊T / every⌋ + 1 frames. A rig with several runs
//! (a slip list, several plate sizes) records them one after the other on one timeline, each
//! run starting one frame interval after the previous one ended; messages carry the run label.
//!
//! The file is finished (summary section and indexes written) by [`Recorder::finish`], which
//! the run calls on success, on a solver error and on Ctrl-C; dropping a recorder finishes it too.

pub mod foxglove;

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use regolith_fsi::Real;
use serde_json::Value;

use super::particles::particle_row;
use super::series::{vehicle_columns, vehicle_values};
use crate::driver::{Observer, RunError, RunStats};
use crate::scene::OutputSpec;
use crate::sim::Simulation;

/// Topic of the soil point cloud.
pub const TOPIC_PARTICLES: &str = "/terrain/particles";
/// Topic of the body frames.
pub const TOPIC_TF: &str = "/tf";
/// Topic of the body shapes.
pub const TOPIC_SHAPES: &str = "/bodies/shapes";
/// Topic of the soil wrenches on bodies.
pub const TOPIC_WRENCH: &str = "/bodies/wrench";

struct Channels {
    particles: u16,
    tf: u16,
    shapes: u16,
    wrench: u16,
    /// Rig and vehicle topics by topic name, with their field names.
    rigs: BTreeMap<String, (u16, Vec<String>)>,
}

/// Writes `recording.mcap` during a run.
pub struct Recorder {
    writer: Option<mcap::Writer<BufWriter<File>>>,
    path: PathBuf,
    channels: Channels,
    spec: OutputSpec,
    sequence: u32,
    /// Run-local time of the next frame (s).
    next: f64,
    /// Time offset of the current run on the recording's timeline (s).
    offset: f64,
    /// Recording time of the last message (s).
    last: f64,
    /// Run label of the current run.
    label: Option<f64>,
    /// The last step produced a frame (rig values go with it).
    frame_now: bool,
    /// Frames written.
    pub frames: u64,
}

impl std::fmt::Debug for Recorder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recorder").field("path", &self.path).field("frames", &self.frames).finish()
    }
}

impl Recorder {
    /// Creates `path` and registers the topics.
    pub fn create(path: &Path, spec: &OutputSpec) -> Result<Self, RunError> {
        let err = |e: &dyn std::fmt::Display| RunError::output(path, e.to_string());
        let file = File::create(path).map_err(|e| err(&e))?;
        let mut w = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .profile("")
            .library(format!("regolith {}", env!("CARGO_PKG_VERSION")))
            .create(BufWriter::new(file))
            .map_err(|e| err(&e))?;
        let mut channel = |topic: &str, schema_name: &str, schema: Value| -> Result<u16, RunError> {
            let data = serde_json::to_vec(&schema).map_err(|e| err(&e))?;
            let id = w.add_schema(schema_name, "jsonschema", &data).map_err(|e| err(&e))?;
            w.add_channel(id, topic, "json", &BTreeMap::new()).map_err(|e| err(&e))
        };
        let channels = Channels {
            particles: channel(TOPIC_PARTICLES, "foxglove.PointCloud", foxglove::point_cloud_schema())?,
            tf: channel(TOPIC_TF, "foxglove.FrameTransforms", foxglove::frame_transforms_schema())?,
            shapes: channel(TOPIC_SHAPES, "foxglove.SceneUpdate", foxglove::scene_update_schema())?,
            wrench: channel(TOPIC_WRENCH, "regolith.BodyWrenches", foxglove::wrench_schema())?,
            rigs: BTreeMap::new(),
        };
        Ok(Self {
            writer: Some(w),
            path: path.to_path_buf(),
            channels,
            spec: spec.clone(),
            sequence: 0,
            next: 0.0,
            offset: 0.0,
            last: 0.0,
            label: None,
            frame_now: false,
            frames: 0,
        })
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn io(&self, e: &dyn std::fmt::Display) -> RunError {
        RunError::output(&self.path, e.to_string())
    }

    fn write(&mut self, channel: u16, t: f64, msg: &Value) -> Result<(), RunError> {
        let data = serde_json::to_vec(msg).map_err(|e| self.io(&e))?;
        let ns = foxglove::nanos(t);
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: self.sequence,
            log_time: ns,
            publish_time: ns,
        };
        self.sequence = self.sequence.wrapping_add(1);
        self.last = self.last.max(t);
        let Some(w) = self.writer.as_mut() else {
            return Err(RunError::output(&self.path, "recording already finished"));
        };
        w.write_to_known_channel(&header, &data).map_err(|e| RunError::output(&self.path, e))
    }

    /// Starts a run (the first, or the next run of a rig): publishes the shapes and the frame at
    /// the run's current time.
    fn begin_run<T: Real>(&mut self, sim: &Simulation<T>, label: Option<f64>) -> Result<(), RunError> {
        if self.frames > 0 {
            self.offset = self.last + self.spec.every;
        }
        self.label = label;
        self.next = sim.time();
        let shapes = sim.frame_shapes();
        if !shapes.is_empty() {
            let t = self.offset + sim.time();
            self.write(self.channels.shapes, t, &foxglove::scene_update(t, &shapes))?;
        }
        self.take_frame(sim)
    }

    /// Takes a frame if one is due after a step.
    fn take_frame<T: Real>(&mut self, sim: &Simulation<T>) -> Result<(), RunError> {
        self.frame_now = false;
        let every = self.spec.every;
        if sim.time() < self.next - 1e-9 * every {
            return Ok(());
        }
        while self.next <= sim.time() + 1e-9 * every {
            self.next += every;
        }
        self.frame(sim)?;
        self.frame_now = true;
        self.frames += 1;
        Ok(())
    }

    fn frame<T: Real>(&mut self, sim: &Simulation<T>) -> Result<(), RunError> {
        let t = self.offset + sim.time();
        if self.spec.particles {
            let data = self.pack_particles(sim);
            self.write(self.channels.particles, t, &foxglove::point_cloud(t, "world", &data))?;
        }
        let frames = sim.frames();
        if !frames.is_empty() {
            self.write(self.channels.tf, t, &foxglove::frame_transforms(t, &frames, &sim.lumped_frames()))?;
        }
        let wrenches = sim.fsi_wrenches();
        if !wrenches.is_empty() {
            let bodies: Vec<Value> = wrenches
                .iter()
                .map(|(name, w)| {
                    serde_json::json!({"name": name, "force": foxglove::xyz(w.force), "torque": foxglove::xyz(w.torque)})
                })
                .collect();
            self.write(
                self.channels.wrench,
                t,
                &serde_json::json!({"timestamp": foxglove::time(t), "bodies": bodies}),
            )?;
        }
        Ok(())
    }

    /// Particles selected by decimation (by particle id, a fixed subset) and the region of
    /// interest, packed as the point-cloud fields.
    fn pack_particles<T: Real>(&self, sim: &Simulation<T>) -> Vec<u8> {
        let s = sim.system.fluid.as_ref();
        let k = self.spec.decimate as u32;
        let mut data = Vec::with_capacity(s.active() / self.spec.decimate.max(1) * foxglove::POINT_STRIDE + 1);
        for i in 0..s.active() {
            if !s.ids()[i].is_multiple_of(k) {
                continue;
            }
            let r = particle_row(s, i);
            if let Some((lo, hi)) = self.spec.roi
                && (0..3).any(|a| r.pos[a] < lo[a] || r.pos[a] > hi[a])
            {
                continue;
            }
            let speed = (r.vel[0] * r.vel[0] + r.vel[1] * r.vel[1] + r.vel[2] * r.vel[2]).sqrt();
            for v in [r.pos[0], r.pos[1], r.pos[2], r.p, r.q, r.pc, speed] {
                data.extend_from_slice(&(v as f32).to_le_bytes());
            }
            data.extend_from_slice(&u32::from(r.material).to_le_bytes());
            data.extend_from_slice(&u32::from(r.water).to_le_bytes());
        }
        data
    }

    /// Records named numbers on `topic` (schema `title`, made from the field names) with the
    /// frame the last step took, if it took one.
    fn record_values<T: Real>(
        &mut self,
        sim: &Simulation<T>,
        topic: &str,
        title: &str,
        fields: &[(&str, f64)],
    ) -> Result<(), RunError> {
        if !self.frame_now {
            return Ok(());
        }
        let names: Vec<String> = fields.iter().map(|(n, _)| n.to_string()).collect();
        let channel = match self.channels.rigs.get(topic) {
            Some((id, known)) if *known == names => *id,
            Some(_) => {
                return Err(RunError::output(
                    &self.path,
                    format!("topic {topic} changed its fields within a recording"),
                ));
            }
            None => {
                let refs: Vec<&str> = fields.iter().map(|(n, _)| *n).collect();
                let schema = serde_json::to_vec(&foxglove::values_schema(title, &refs)).map_err(|e| self.io(&e))?;
                let path = self.path.clone();
                let err = |e: mcap::McapError| RunError::output(&path, e);
                let Some(w) = self.writer.as_mut() else { return Ok(()) };
                let sid = w.add_schema(title, "jsonschema", &schema).map_err(err)?;
                let id = w.add_channel(sid, topic, "json", &BTreeMap::new()).map_err(err)?;
                self.channels.rigs.insert(topic.to_string(), (id, names));
                id
            }
        };
        let t = self.offset + sim.time();
        let mut msg = serde_json::Map::new();
        msg.insert("timestamp".into(), foxglove::time(t));
        msg.insert("run".into(), self.label.map_or(Value::Null, Value::from));
        for (n, v) in fields {
            // JSON has no NaN: a quantity that is undefined at this frame is written as null.
            msg.insert((*n).into(), if v.is_finite() { Value::from(*v) } else { Value::Null });
        }
        self.write(channel, t, &Value::Object(msg))
    }

    /// Writes the summary section and closes the file. Idempotent.
    pub fn finish(&mut self) -> Result<(), RunError> {
        if let Some(mut w) = self.writer.take() {
            w.finish().map_err(|e| self.io(&e))?;
            let mut inner = w.into_inner();
            std::io::Write::flush(&mut inner).map_err(|e| self.io(&e))?;
        }
        Ok(())
    }
}

impl Recorder {
    /// Records every vehicle's pose, speed and wheel states on `/vehicles/<name>` with the
    /// frame the last step took, if it took one.
    fn vehicles<T: Real>(&mut self, sim: &Simulation<T>) -> Result<(), RunError> {
        for (vi, v) in sim.scene.vehicles.iter().enumerate() {
            let names = vehicle_columns(v);
            let values = vehicle_values(sim, vi);
            let fields: Vec<(&str, f64)> = names.iter().map(String::as_str).zip(values).collect();
            self.record_values(sim, &format!("/vehicles/{}", v.name), "regolith.Vehicle", &fields)?;
        }
        Ok(())
    }
}

impl<T: Real> Observer<T> for Recorder {
    fn begin(&mut self, sim: &Simulation<T>, label: Option<f64>) -> Result<(), RunError> {
        self.begin_run(sim, label)?;
        self.vehicles(sim)
    }

    fn after_step(&mut self, sim: &Simulation<T>, _stats: &RunStats) -> Result<(), RunError> {
        self.take_frame(sim)?;
        self.vehicles(sim)
    }

    fn values(
        &mut self,
        sim: &Simulation<T>,
        topic: &str,
        title: &str,
        fields: &[(&str, f64)],
    ) -> Result<(), RunError> {
        self.record_values(sim, topic, title, fields)
    }

    fn finish(&mut self) -> Result<(), RunError> {
        Recorder::finish(self)
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        let _ = self.finish();
    }
}

/// What a recording holds.
#[derive(Clone, Debug, PartialEq)]
pub struct TopicInfo {
    /// Topic.
    pub topic: String,
    /// Schema name (empty when the channel has none).
    pub schema: String,
    /// Message encoding.
    pub encoding: String,
    /// Messages on it.
    pub messages: u64,
    /// First and last log time (s).
    pub range: Option<(f64, f64)>,
}

/// Reads every message of a recording and tallies them per topic. Reading the messages
/// (rather than trusting the summary's statistics) also checks that every chunk decompresses
/// and every record parses.
pub fn topics(bytes: &[u8]) -> Result<Vec<TopicInfo>, String> {
    let mut out: Vec<TopicInfo> = Vec::new();
    for m in mcap::MessageStream::new(bytes).map_err(|e| e.to_string())? {
        let m = m.map_err(|e| e.to_string())?;
        let t = m.log_time as f64 * 1e-9;
        let i = match out.iter().position(|x| x.topic == m.channel.topic) {
            Some(i) => i,
            None => {
                out.push(TopicInfo {
                    topic: m.channel.topic.clone(),
                    schema: m.channel.schema.as_ref().map(|s| s.name.clone()).unwrap_or_default(),
                    encoding: m.channel.message_encoding.clone(),
                    messages: 0,
                    range: None,
                });
                out.len() - 1
            }
        };
        let x = &mut out[i];
        x.messages += 1;
        x.range = Some(x.range.map_or((t, t), |(a, b)| (a.min(t), b.max(t))));
    }
    out.sort_by(|a, b| a.topic.cmp(&b.topic));
    Ok(out)
}
