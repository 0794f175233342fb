//! [`ActiveRegion`]: what a backend keeps between steps to follow an active region (see
//! [`crate::active`]), and the classification itself. The CPU backend and the wgpu backend
//! (which classifies on the host) share it, so both give every particle the same role.

use rayon::prelude::*;
use regolith_body::BodyState;

use super::grid::{CellIndexer, GridSpec};
use super::neighbors;
use crate::Real;
use crate::active::{ActiveDomain, ActiveSettings, Role, RoleCounts, WorldBox};
use crate::math::Vec3;

/// The active region of a solver: the settings and boxes, where the boxes are now and where
/// they were at the last classification, and the cells awake particles may be in until the
/// next one.
#[derive(Clone, Debug, Default)]
pub struct ActiveRegion {
    domain: Option<ActiveDomain>,
    boxes_now: Vec<WorldBox>,
    classified: Option<Vec<WorldBox>>,
    awake_cells: Vec<bool>,
    classifications: u64,
}

/// The result of a classification: the new soil order and how many of each role.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Classification {
    /// New position `k` takes the particle at `order[k]`: awake, extended, asleep, outside,
    /// each in its earlier order.
    pub order: Vec<u32>,
    /// Particles of each role, indexed by `Role as usize`.
    pub count: [usize; 4],
}

impl ActiveRegion {
    /// Cells past those awake particles held at a classification that they may drift into
    /// before the next one (on every side). The slack keeps the boundary particles' jitter
    /// across cell faces from forcing a classification every few steps.
    pub const SLACK: usize = 1;

    /// Keeps `domain` from now on (`None`: the whole domain is awake). Checks the settings and
    /// that there is one box per FSI body (`bodies`); errors name what is wrong.
    pub fn set(&mut self, domain: Option<ActiveDomain>, bodies: usize, wet: bool) -> Result<(), String> {
        if let Some(d) = &domain {
            if wet {
                return Err("active domains are not available with water yet: keep the whole domain active".into());
            }
            if let Err((key, msg)) = d.settings.validate() {
                return Err(format!("active domain {key} {msg}"));
            }
            if d.boxes.len() != bodies {
                return Err(format!("active domain has {} boxes for {bodies} bodies", d.boxes.len()));
            }
        }
        self.domain = domain;
        self.boxes_now.clear();
        self.classified = None;
        Ok(())
    }

    /// The domain kept, if any.
    pub fn domain(&self) -> Option<&ActiveDomain> {
        self.domain.as_ref()
    }

    /// Places the boxes from the bodies' states (owner order).
    pub fn place(&mut self, states: &[BodyState]) {
        if let Some(d) = &self.domain {
            self.boxes_now.clear();
            self.boxes_now.extend(d.boxes.iter().zip(states).map(|(b, s)| b.place(s)));
        }
    }

    /// True while the region is kept at `time`: a domain with boxes, placed, after the
    /// free-flow time.
    pub fn partitioned(&self, time: f64) -> bool {
        self.domain.as_ref().is_some_and(|d| {
            !d.boxes.is_empty() && self.boxes_now.len() == d.boxes.len() && time >= d.settings.free_flow_time
        })
    }

    /// True when the last classification no longer holds: none made yet, or some box has
    /// moved farther than the travel allowance since.
    pub fn needs_classification(&self) -> bool {
        let Some(d) = &self.domain else { return false };
        match &self.classified {
            None => true,
            Some(old) => {
                old.len() != self.boxes_now.len()
                    || self.boxes_now.iter().zip(old).any(|(b, o)| b.drift_from(o) > d.settings.travel)
            }
        }
    }

    /// Forgets the last classification (the next partitioned step makes one).
    pub fn forget(&mut self) {
        self.classified = None;
    }

    /// The boxes where the bodies are now (owner order; empty before `place`).
    pub fn boxes(&self) -> &[WorldBox] {
        &self.boxes_now
    }

    /// Records a classification made by a device's twin of [`Self::classify`] with the boxes
    /// where they are now: the next one is due when they have moved the travel allowance from
    /// here. (`awake_cells` is then the device's, not kept here.)
    pub fn note_classification(&mut self) {
        self.classified = Some(self.boxes_now.clone());
        self.classifications += 1;
    }

    /// Cells awake particles may be in until the next classification (linear cell index).
    pub fn awake_cells(&self) -> &[bool] {
        &self.awake_cells
    }

    /// Classifications made so far.
    pub fn classifications(&self) -> u64 {
        self.classifications
    }

    /// Gives each particle its role with the boxes where they are now, and returns the order
    /// that puts the particles into awake | extended | asleep | outside. `radius` is the
    /// kernel support 2h (m).
    pub fn classify<T: Real>(
        &mut self,
        grid: &GridSpec,
        pos: &[Vec3<T>],
        vel: &[Vec3<T>],
        radius: f64,
    ) -> Classification {
        let Some(d) = &self.domain else {
            return Classification { order: (0..pos.len() as u32).collect(), count: [pos.len(), 0, 0, 0] };
        };
        let roles = roles(grid, pos, vel, &self.boxes_now, &d.settings, radius, &mut self.awake_cells);
        let mut count = [0usize; 4];
        for &r in &roles {
            count[r as usize] += 1;
        }
        let mut next = [0, count[0], count[0] + count[1], count[0] + count[1] + count[2]];
        let mut order = vec![0u32; pos.len()];
        for (i, &r) in roles.iter().enumerate() {
            order[next[r as usize]] = i as u32;
            next[r as usize] += 1;
        }
        self.classified = Some(self.boxes_now.clone());
        self.classifications += 1;
        Classification { order, count }
    }

    /// The roles the particles would get if classified with the boxes placed at `states`
    /// (what `regolith check` reports before a run; ignores the free-flow time).
    pub fn expected<T: Real>(
        &self,
        grid: &GridSpec,
        pos: &[Vec3<T>],
        vel: &[Vec3<T>],
        radius: f64,
        states: &[BodyState],
    ) -> Option<RoleCounts> {
        let d = self.domain.as_ref()?;
        let boxes: Vec<WorldBox> = d.boxes.iter().zip(states).map(|(b, s)| b.place(s)).collect();
        let roles = roles(grid, pos, vel, &boxes, &d.settings, radius, &mut Vec::new());
        let count = |r: Role| roles.iter().filter(|&&x| x == r).count();
        Some(RoleCounts { awake: count(Role::Awake), extended: count(Role::Extended), asleep: count(Role::Asleep) })
    }

    /// Bytes held (capacity).
    pub fn heap_bytes(&self) -> usize {
        let boxes = self.boxes_now.capacity() + self.classified.as_ref().map_or(0, Vec::capacity);
        self.awake_cells.capacity() + boxes * size_of::<WorldBox>()
    }
}

/// The role of each particle (see [`crate::active`]): awake inside a box grown by the travel
/// allowance or faster than the sleep speed, extended within one cell plus the search reach of
/// a cell holding an awake particle, asleep otherwise, outside off the grid. `awake_cells`
/// receives the cells awake particles may move in until the next classification (those they
/// hold and one more on every side).
fn roles<T: Real>(
    grid: &GridSpec,
    pos: &[Vec3<T>],
    vel: &[Vec3<T>],
    boxes: &[WorldBox],
    settings: &ActiveSettings,
    radius: f64,
    awake_cells: &mut Vec<bool>,
) -> Vec<Role> {
    let idx = CellIndexer::<T>::new(grid);
    let v2 = settings.sleep_speed * settings.sleep_speed;
    let outside = u32::MAX;
    let (cell, mut roles): (Vec<u32>, Vec<Role>) = pos
        .par_iter()
        .zip(vel.par_iter())
        .map(|(p, v)| match idx.coords(*p) {
            None => (outside, Role::Outside),
            Some(c) => {
                let x = p.as_f64();
                let awake = v.as_f64().iter().map(|a| a * a).sum::<f64>() > v2
                    || boxes.iter().any(|b| b.contains(x, settings.travel));
                (idx.linear(c) as u32, if awake { Role::Awake } else { Role::Asleep })
            }
        })
        .unzip();
    let dims = grid.dims;
    let mut held = vec![false; grid.cells()];
    for (&c, &r) in cell.iter().zip(&roles) {
        if r == Role::Awake {
            held[c as usize] = true;
        }
    }
    // Awake particles may drift `SLACK` cells past the cells they held before the
    // classification must be redone; the extended band reaches the search reach past that, so
    // every awake particle's neighbours stay awake or extended meanwhile.
    const SLACK: usize = ActiveRegion::SLACK;
    let reach = neighbors::reach(radius, grid.cell);
    *awake_cells = dilate(&held, dims, SLACK);
    let near = dilate(&held, dims, SLACK + reach);
    roles.par_iter_mut().zip(cell.par_iter()).for_each(|(r, &c)| {
        if *r == Role::Asleep && near[c as usize] {
            *r = Role::Extended;
        }
    });
    roles
}

/// The cells within `r` cells (along every axis: a cube) of a marked cell.
fn dilate(mask: &[bool], dims: [usize; 3], r: usize) -> Vec<bool> {
    let mut cur = mask.to_vec();
    let stride = [dims[1] * dims[2], dims[2], 1];
    for axis in 0..3 {
        let mut next = cur.clone();
        for (c, _) in cur.iter().enumerate().filter(|(_, m)| **m) {
            let i = c / stride[axis] % dims[axis];
            let base = c - i * stride[axis];
            for j in i.saturating_sub(r)..=(i + r).min(dims[axis] - 1) {
                next[base + j * stride[axis]] = true;
            }
        }
        cur = next;
    }
    cur
}
