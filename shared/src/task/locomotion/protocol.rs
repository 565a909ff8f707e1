//! The locomotion protocol (paper §IV) on the dynamic simulator: keep the largest body, settle it
//! on the floor under gravity, record the centre of mass, actuate for a number of cycles, and
//! score the centre of mass's travel along the heading. The simulator knows nothing of this.

use serde::{Deserialize, Serialize};

use super::starts::Starts;
use crate::dynamics::{Divergence, DivergenceReason, DynamicScene, Simulation, Vec3};
use crate::material::Palette;
use crate::task::SceneError;
use crate::task::error::positive;
use crate::voxel::{VoxelGrid, keep_largest_component};

/// The settle → actuate → score sequence, with its units and defaults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LocomotionProtocol {
    /// How the body settles under gravity before actuation starts.
    pub settle: SettleRule,
    /// Number of actuation cycles after settling. Default 10 (the paper's).
    pub actuation_cycles: u32,
    /// How the centre of mass's travel becomes the fitness.
    pub fitness: LocomotionFitness,
    /// The direction travel is scored along, rad from +X towards +Y. Default 0 (+X).
    pub heading: f64,
    /// How many times the settled body is switched on; the median start is scored.
    pub starts: Starts,
}

impl Default for LocomotionProtocol {
    fn default() -> Self {
        Self {
            settle: SettleRule::default(),
            actuation_cycles: 10,
            fitness: LocomotionFitness::default(),
            heading: 0.0,
            starts: Starts::default(),
        }
    }
}

impl LocomotionProtocol {
    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), SceneError> {
        let s = &self.settle;
        if !(s.max_time.is_finite() && s.max_time >= 0.0) {
            return Err(SceneError::new(
                "settle.max_time",
                format!("{} must be a non-negative number of seconds", s.max_time),
            ));
        }
        if !(s.still_speed.is_finite() && s.still_speed >= 0.0) {
            return Err(SceneError::new(
                "settle.still_speed",
                format!("{} must be a non-negative speed", s.still_speed),
            ));
        }
        positive("settle.check_interval", s.check_interval)?;
        if let Some(zeta) = s.damping
            && !(zeta.is_finite() && (0.0..=1.5).contains(&zeta))
        {
            return Err(SceneError::new(
                "settle.damping",
                format!(
                    "{zeta} must be a damping ratio from 0 to 1.5 (above, the time step is unstable)"
                ),
            ));
        }
        self.starts.validate()?;
        if self.actuation_cycles == 0 {
            return Err(SceneError::new(
                "actuation_cycles",
                "must be at least 1 (no cycle, no gait)",
            ));
        }
        Ok(())
    }

    /// The unit vector travel is scored along, in the floor plane.
    fn direction(&self) -> (f64, f64) {
        (self.heading.cos(), self.heading.sin())
    }

    /// Travel from `a` to `b` along the heading and across it (to its left). Along +X the
    /// travel is exactly b.x − a.x, as before headings existed.
    pub(super) fn travel(&self, a: [f64; 3], b: [f64; 3]) -> (f64, f64) {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        if self.heading == 0.0 {
            return (dx, dy);
        }
        let (c, s) = self.direction();
        (dx * c + dy * s, -dx * s + dy * c)
    }

    /// The fitness of a centre-of-mass trace (settled, then after each cycle), as
    /// [`LocomotionFitness`] says.
    pub(super) fn score(&self, trace: &[[f64; 3]]) -> f64 {
        match self.fitness {
            LocomotionFitness::TotalDisplacement => match (trace.first(), trace.last()) {
                (Some(&a), Some(&b)) => self.travel(a, b).0,
                _ => 0.0,
            },
            LocomotionFitness::SteadyGait => {
                let per_cycle: Vec<f64> = trace
                    .windows(2)
                    .map(|w| self.travel(w[0], w[1]).0)
                    .collect();
                let cycles = per_cycle.len() as f64;
                median(per_cycle) * cycles
            }
        }
    }

    /// The paper's Table IV speed: travel per cycle in % of body length.
    pub(super) fn speed_percent_per_cycle(&self, travel: f64, body_length: f64) -> f64 {
        let cycles = f64::from(self.actuation_cycles.max(1));
        100.0 * travel / body_length / cycles
    }
}

/// When settling under gravity ends: when every voxel is slower than `still_speed`, checked every
/// `check_interval` seconds, or at `max_time`, whichever comes first.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SettleRule {
    /// Longest settling time, s. Default 0.5 (the reference evaluation's).
    pub max_time: f64,
    /// Speed under which the body counts as still, m/s. Default 1e-3 (one voxel per second at
    /// 1 mm voxels). 0 means always settle for `max_time`.
    pub still_speed: f64,
    /// How often stillness is checked, s. Default 0.01.
    pub check_interval: f64,
    /// The global damping ratio (`dynamics.damping.global`, of each voxel's own critical
    /// damping) while settling, the scene's own applying again when actuation starts; `None`
    /// (the default) settles with the scene's own, as the paper's protocol does. Not on by
    /// default because no one value settles every body sooner: measured
    /// (docs/explanation/physics.md), ζ = 0.1 saves 20 % of the steps over six random 20³ robots
    /// and 8 % over twenty at 10³, but overdamps the slow sway of a thin overhang into a creep that
    /// settles 5× later than link damping alone; ζ = 0.005 settles that overhang sooner but
    /// doubles the settle of some robots.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
}

impl Default for SettleRule {
    fn default() -> Self {
        Self {
            max_time: 0.5,
            still_speed: 1e-3,
            check_interval: 0.01,
            damping: None,
        }
    }
}

/// How a locomotion evaluation turns the centre of mass's per-cycle travel into a fitness.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LocomotionFitness {
    /// The median of the per-cycle travels times the number of cycles (default). For a periodic
    /// gait it equals the total travel; a one-off jump does not count. Why: random and early
    /// designs are often tall bodies that the actuation tips over, and a topple moves the centre
    /// of mass by about the body's height in one or two cycles (measured: 10–17 mm, 5–12 % of
    /// body length per cycle, in the first 100 evaluations of `configs/locomotion.toml`), more
    /// than any gait; scored on total travel, evolution breeds bodies that fall over.
    #[default]
    SteadyGait,
    /// The paper's literal measure: centre of mass at the end of the last cycle minus at the end of
    /// settling.
    TotalDisplacement,
}

/// How a locomotion evaluation ended.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum LocomotionStatus {
    /// Settled and actuated for every cycle; the fitness is meaningful.
    Completed,
    /// Stopped at `time` (s) for `reason`; the fitness is 0.
    Diverged { reason: DivergenceReason, time: f64 },
    /// The design has no voxels.
    Empty,
    /// The scene or palette is invalid (the message names the field).
    Invalid { message: String },
}

/// The result of [`simulate_locomotion`]. Every number is finite.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LocomotionOutcome {
    pub status: LocomotionStatus,
    /// Travel of the centre of mass along the heading as the protocol's [`LocomotionFitness`]
    /// measures it, m (0 unless completed).
    pub fitness: f64,
    /// Displacement of the centre of mass along the heading from the end of settling to the end
    /// of the last actuation cycle, m (0 unless completed).
    pub displacement: f64,
    /// Displacement across the heading (positive to its left) over the same time, m.
    pub lateral: f64,
    /// fitness / body length / cycles, in % of body length per cycle (paper's Table IV measure).
    pub speed_percent_per_cycle: f64,
    /// Extent of the body along the heading at rest, m.
    pub body_length: f64,
    pub voxel_count: usize,
    pub steps: u64,
    /// Simulated time, s (settling plus actuation).
    pub simulated_time: f64,
    /// How long settling took, s.
    pub settle_time: f64,
    /// Time step used, s.
    pub dt: f64,
    /// Centre of mass at the end of settling and after each actuation cycle, m.
    pub centre_of_mass_trace: Vec<[f64; 3]>,
    /// With several starts, each start's fitness in start order (m); the other fields describe
    /// the median start. Empty for a single start.
    pub start_fitness: Vec<f64>,
}

impl LocomotionOutcome {
    fn failed(status: LocomotionStatus, voxel_count: usize) -> Self {
        Self {
            status,
            fitness: 0.0,
            displacement: 0.0,
            lateral: 0.0,
            speed_percent_per_cycle: 0.0,
            body_length: 0.0,
            voxel_count,
            steps: 0,
            simulated_time: 0.0,
            settle_time: 0.0,
            dt: 0.0,
            centre_of_mass_trace: Vec::new(),
            start_fitness: Vec::new(),
        }
    }

    /// The fitness if the evaluation completed.
    pub fn completed_fitness(&self) -> Option<f64> {
        (self.status == LocomotionStatus::Completed).then_some(self.fitness)
    }
}

/// Where a locomotion simulation is when it calls its observer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LocomotionPhase {
    /// After each settling check (every `settle.check_interval`).
    Settling,
    /// Settling has ended; actuation starts next.
    Settled,
    /// After sample `sample` (1-based) of `samples_per_cycle` in actuation cycle `cycle` (0-based).
    Actuating { cycle: u32, sample: u32 },
}

/// Evaluates a design for forward locomotion. Deterministic bit for bit; never panics on a
/// design (degenerate inputs become a status).
pub fn simulate_locomotion(
    grid: &VoxelGrid,
    palette: &Palette,
    scene: &DynamicScene,
    protocol: &LocomotionProtocol,
) -> LocomotionOutcome {
    evaluate(grid, palette, scene, protocol, None)
}

/// [`simulate_locomotion`] that also hands the simulation to `observer` at every settling check
/// and `samples_per_cycle` times per actuation cycle (evenly in steps), for recordings such as a
/// dense centre-of-mass trace or animation frames. The observer runs between chunks of steps,
/// never inside the step loop, and the chunks add up to the same steps, so the outcome is bit
/// for bit that of [`simulate_locomotion`]. With several starts it sees the median start's cycles.
pub fn simulate_locomotion_observed(
    grid: &VoxelGrid,
    palette: &Palette,
    scene: &DynamicScene,
    protocol: &LocomotionProtocol,
    samples_per_cycle: u32,
    observer: &mut dyn FnMut(LocomotionPhase, &Simulation),
) -> LocomotionOutcome {
    let observer = Observer {
        samples_per_cycle: samples_per_cycle.max(1),
        call: observer,
    };
    evaluate(grid, palette, scene, protocol, Some(observer))
}

/// Who watches a simulation, and how often per cycle.
struct Observer<'a> {
    samples_per_cycle: u32,
    call: &'a mut dyn FnMut(LocomotionPhase, &Simulation),
}

fn notify(observer: &mut Option<Observer>, phase: LocomotionPhase, sim: &Simulation) {
    if let Some(o) = observer {
        (o.call)(phase, sim);
    }
}

fn evaluate(
    grid: &VoxelGrid,
    palette: &Palette,
    scene: &DynamicScene,
    protocol: &LocomotionProtocol,
    observer: Option<Observer>,
) -> LocomotionOutcome {
    let body = keep_largest_component(grid);
    let voxel_count = body.filled_count();
    if voxel_count == 0 {
        return LocomotionOutcome::failed(LocomotionStatus::Empty, 0);
    }
    let mut sim = match Simulation::new(&body, palette, scene) {
        Ok(sim) => sim,
        Err(e) => {
            return LocomotionOutcome::failed(
                LocomotionStatus::Invalid {
                    message: e.to_string(),
                },
                voxel_count,
            );
        }
    };
    let body_length = body_length(sim.cells(), scene.voxel_size, protocol.heading);
    let mut outcome = LocomotionOutcome {
        body_length,
        dt: sim.dt(),
        ..LocomotionOutcome::failed(LocomotionStatus::Completed, voxel_count)
    };
    let result = run(&mut sim, scene, protocol, observer, &mut outcome);
    outcome.steps = sim.steps();
    outcome.simulated_time = sim.time();
    if let Err(d) = result {
        outcome.status = LocomotionStatus::Diverged {
            reason: d.reason,
            time: d.time,
        };
        outcome.fitness = 0.0;
        outcome.displacement = 0.0;
        outcome.lateral = 0.0;
        outcome.speed_percent_per_cycle = 0.0;
        outcome.start_fitness.clear();
    }
    outcome
}

/// Extent of the body along `heading`: the projections of its voxel centres' span plus one
/// voxel's projected width. Along +X it is the count of occupied X columns times the voxel size.
fn body_length(cells: &[[u16; 3]], voxel_size: f64, heading: f64) -> f64 {
    if heading == 0.0 {
        let (min_x, max_x) = cells
            .iter()
            .fold((u16::MAX, 0), |(lo, hi), c| (lo.min(c[0]), hi.max(c[0])));
        return f64::from(max_x - min_x + 1) * voxel_size;
    }
    let (c, s) = (heading.cos(), heading.sin());
    let (lo, hi) = cells
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            let p = f64::from(v[0]) * c + f64::from(v[1]) * s;
            (lo.min(p), hi.max(p))
        });
    (hi - lo + c.abs() + s.abs()) * voxel_size
}

fn to_array(c: Vec3) -> [f64; 3] {
    [c.x, c.y, c.z]
}

/// Settles, then actuates (once per start), then scores; `sim` ends as the scored start's.
fn run(
    sim: &mut Simulation,
    scene: &DynamicScene,
    protocol: &LocomotionProtocol,
    mut observer: Option<Observer>,
    outcome: &mut LocomotionOutcome,
) -> Result<(), Divergence> {
    settle(sim, scene, &protocol.settle, &mut observer)?;
    outcome.settle_time = sim.time();
    outcome
        .centre_of_mass_trace
        .push(to_array(sim.centre_of_mass()));
    if let Some(actuation) = &scene.actuation {
        let starts = &protocol.starts;
        if starts.count <= 1 {
            actuate(
                sim,
                protocol,
                &mut observer,
                &mut outcome.centre_of_mass_trace,
            )?;
        } else {
            // Every start leaves from the same settled state: the settle is paid once.
            let settled = sim.clone();
            let start = |k: usize| {
                let mut s = settled.clone();
                s.set_actuation_phase(actuation.phase + starts.phase(k));
                s
            };
            let mut runs = Vec::with_capacity(starts.count as usize);
            for k in 0..starts.count as usize {
                let (mut s, mut trace) = (start(k), outcome.centre_of_mass_trace.clone());
                actuate(&mut s, protocol, &mut None, &mut trace)?;
                runs.push((s, trace));
            }
            outcome.start_fitness = runs.iter().map(|(_, t)| protocol.score(t)).collect();
            let median = Starts::median_start(&outcome.start_fitness);
            if observer.is_some() {
                // The same start again, watched: the same steps give the same bits.
                let mut trace = outcome.centre_of_mass_trace.clone();
                actuate(&mut start(median), protocol, &mut observer, &mut trace)?;
            }
            (*sim, outcome.centre_of_mass_trace) = runs.swap_remove(median);
        }
    }
    let trace = &outcome.centre_of_mass_trace;
    (outcome.displacement, outcome.lateral) = protocol.travel(trace[0], trace[trace.len() - 1]);
    outcome.fitness = protocol.score(trace);
    outcome.speed_percent_per_cycle =
        protocol.speed_percent_per_cycle(outcome.fitness, outcome.body_length);
    Ok(())
}

/// Lets the body fall and come to rest under gravity, as `rule` says.
fn settle(
    sim: &mut Simulation,
    scene: &DynamicScene,
    rule: &SettleRule,
    observer: &mut Option<Observer>,
) -> Result<(), Divergence> {
    let validated = "settle.damping and dynamics.damping.global are validated with the scene";
    if let Some(zeta) = rule.damping {
        sim.set_global_damping(zeta).expect(validated);
    }
    while sim.time() < rule.max_time {
        let chunk = rule.check_interval.min(rule.max_time - sim.time());
        sim.run_for(chunk)?;
        notify(observer, LocomotionPhase::Settling, sim);
        if rule.still_speed > 0.0 && sim.max_speed() < rule.still_speed {
            break;
        }
    }
    if rule.damping.is_some() {
        sim.set_global_damping(scene.damping.global)
            .expect(validated);
    }
    notify(observer, LocomotionPhase::Settled, sim);
    Ok(())
}

/// Switches the actuation on and runs the protocol's cycles, appending the centre of mass after
/// each to `trace`.
fn actuate(
    sim: &mut Simulation,
    protocol: &LocomotionProtocol,
    observer: &mut Option<Observer>,
    trace: &mut Vec<[f64; 3]>,
) -> Result<(), Divergence> {
    let Some(actuation) = sim.scene().actuation.clone() else {
        return Ok(());
    };
    sim.start_actuation();
    let steps_per_cycle = (actuation.period / sim.dt()).round().max(1.0) as u64;
    let samples_per_cycle = observer.as_ref().map_or(1, |o| o.samples_per_cycle);
    let samples = u64::from(samples_per_cycle);
    for cycle in 0..protocol.actuation_cycles {
        // Sample k ends at step round(k · steps / samples) of the cycle.
        let mut done = 0;
        for sample in 1..=samples_per_cycle {
            let end = (u64::from(sample) * steps_per_cycle + samples / 2) / samples;
            sim.run_steps(end - done)?;
            done = end;
            notify(observer, LocomotionPhase::Actuating { cycle, sample }, sim);
        }
        trace.push(to_array(sim.centre_of_mass()));
    }
    Ok(())
}

/// The median (mean of the middle two for an even count), 0 for none. Values are finite here:
/// a non-finite state ends the simulation as a divergence first.
fn median(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

#[cfg(test)]
mod tests;
