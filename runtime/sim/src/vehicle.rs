//! One simulated vehicle: its state and its kinematics (no DataServer here).

use mocu_dataserver::Guid;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VehicleKind {
    Usv,
    Ugv,
    Uav,
}

impl VehicleKind {
    pub fn type_name(self) -> &'static str {
        match self {
            VehicleKind::Usv => "usv",
            VehicleKind::Ugv => "ugv",
            VehicleKind::Uav => "uav",
        }
    }

    pub(crate) fn subtype(self) -> &'static str {
        match self {
            VehicleKind::Usv => "boat",
            VehicleKind::Ugv => "rover",
            VehicleKind::Uav => "quadrotor",
        }
    }

    /// Top speed (m/s), speed lag (s), turn rate at full rudder (deg/s), fuel used per
    /// second at full throttle, link range (m).
    pub(crate) fn params(self) -> Params {
        match self {
            VehicleKind::Usv => Params {
                max_speed: 8.0,
                tau: 2.5,
                max_turn: 20.0,
                burn: 1.0 / 1800.0,
                link_range: 3000.0,
            },
            VehicleKind::Ugv => Params {
                max_speed: 3.0,
                tau: 0.8,
                max_turn: 45.0,
                burn: 1.0 / 1200.0,
                link_range: 1500.0,
            },
            VehicleKind::Uav => Params {
                max_speed: 15.0,
                tau: 1.5,
                max_turn: 60.0,
                burn: 1.0 / 900.0,
                link_range: 5000.0,
            },
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct Params {
    pub max_speed: f64,
    pub tau: f64,
    pub max_turn: f64,
    pub burn: f64,
    pub link_range: f64,
}

/// What steers the vehicle.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Guidance {
    /// The operator's goal throttle and rudder.
    Manual,
    /// To a point (goto, or home for return_home); holds there.
    Point { x: f64, y: f64, home: bool },
    /// Along a route's waypoints (local metres), index of the next one.
    /// `repeat`: start over after the last waypoint (a patrol).
    Route { route: Guid, points: Vec<(f64, f64)>, next: usize, repeat: bool },
    /// Stay put.
    Hold,
}

pub(crate) struct Camera {
    pub listener: Guid,
    pub lens: crate::camera::Lens,
    pub frames: u64,
    pub next_due: f64,
    /// Made on the first frame someone receives (its scene is drawn once).
    pub renderer: Option<crate::camera::Renderer>,
}

pub(crate) struct Vehicle {
    pub name: String,
    pub kind: VehicleKind,
    pub guid: Guid,
    pub nav: Guid,
    pub cameras: Vec<Camera>,
    /// The payload camera's head: pan (deg, right of the bow) and tilt (deg, up).
    pub pan: f64,
    pub tilt: f64,
    /// The manipulator of a UGV.
    pub manipulator: Option<crate::manipulator::Manipulator>,
    pub x: f64,
    pub y: f64,
    pub alt: f64,
    pub target_alt: f64,
    pub heading: f64,
    pub speed: f64,
    pub roll: f64,
    pub pitch: f64,
    pub fuel: f64,
    pub armed: bool,
    pub engine: bool,
    pub control: String,
    pub guidance: Guidance,
    pub home: (f64, f64),
    pub link: f64,
}

/// Arrival radius for points and waypoints (m).
const ARRIVE: f64 = 5.0;

impl Vehicle {
    pub(crate) fn mode(&self) -> &'static str {
        match self.guidance {
            Guidance::Manual => "manual",
            Guidance::Point { home: true, .. } => "rtl",
            Guidance::Point { .. } => "guided",
            Guidance::Route { .. } => "route",
            Guidance::Hold => "hold",
        }
    }

    /// Advances the vehicle by `dt` seconds. `goal` is the operator's (throttle %, rudder
    /// deg); `noise` a uniform number in [0, 1) for the link.
    pub(crate) fn step(&mut self, dt: f64, goal: (f64, f64), noise: f64) {
        let p = self.kind.params();
        let (mut throttle, rudder) = match &mut self.guidance {
            Guidance::Manual => goal,
            Guidance::Hold => (0.0, 0.0),
            Guidance::Point { x, y, .. } => steer(self.x, self.y, self.heading, *x, *y),
            Guidance::Route { points, next, .. } => {
                while *next < points.len()
                    && dist(self.x, self.y, points[*next].0, points[*next].1) < ARRIVE
                {
                    *next += 1;
                }
                match points.get(*next) {
                    Some(&(x, y)) => steer(self.x, self.y, self.heading, x, y),
                    None => (0.0, 0.0),
                }
            }
        };
        if let Guidance::Point { x, y, .. } = self.guidance
            && dist(self.x, self.y, x, y) < ARRIVE
        {
            throttle = 0.0;
        }
        if let Guidance::Route { ref mut next, ref points, repeat, .. } = self.guidance
            && *next >= points.len()
        {
            if repeat {
                *next = 0;
            } else {
                self.guidance = Guidance::Hold;
            }
        }
        let running = self.engine && self.armed && self.fuel > 0.0;
        if !running {
            throttle = 0.0;
        }
        let floor = if self.kind == VehicleKind::Uav { 0.0 } else { -30.0 };
        let throttle = throttle.clamp(floor, 100.0);
        let target = throttle / 100.0 * p.max_speed;
        self.speed += (target - self.speed) * (1.0 - (-dt / p.tau).exp());
        let authority = (self.speed.abs() / (0.3 * p.max_speed)).min(1.0);
        let authority =
            if self.kind == VehicleKind::Ugv && running { authority.max(0.5) } else { authority };
        let turn = rudder.clamp(-30.0, 30.0) / 30.0 * p.max_turn * authority;
        self.heading = (self.heading + turn * dt).rem_euclid(360.0);
        let h = self.heading.to_radians();
        self.x += self.speed * h.sin() * dt;
        self.y += self.speed * h.cos() * dt;
        self.roll = if self.kind == VehicleKind::Ugv { 0.0 } else { turn / p.max_turn * 20.0 };
        self.pitch = (target - self.speed) / p.max_speed * 10.0;
        if self.kind == VehicleKind::Uav {
            let want = if running { self.target_alt } else { 0.0 };
            let climb = if running { 3.0 } else { 1.5 };
            self.alt += (want - self.alt).clamp(-climb * dt, climb * dt);
        }
        if self.engine {
            self.fuel -= p.burn * (0.05 + throttle.abs() / 100.0) * dt;
            if self.fuel <= 0.0 {
                self.fuel = 0.0;
                self.engine = false;
            }
        }
        let d = dist(self.x, self.y, 0.0, 0.0);
        self.link = ((1.0 - d / p.link_range) - 0.02 * noise).clamp(0.0, 1.0);
    }
}

pub(crate) fn dist(ax: f64, ay: f64, bx: f64, by: f64) -> f64 {
    ((ax - bx).powi(2) + (ay - by).powi(2)).sqrt()
}

/// Throttle (%) and rudder (deg) toward a point.
fn steer(x: f64, y: f64, heading: f64, tx: f64, ty: f64) -> (f64, f64) {
    let bearing = (tx - x).atan2(ty - y).to_degrees().rem_euclid(360.0);
    let err = (bearing - heading + 540.0).rem_euclid(360.0) - 180.0;
    let d = dist(x, y, tx, ty);
    let throttle = (d * 4.0).min(80.0) * if err.abs() > 90.0 { 0.3 } else { 1.0 };
    (throttle, (err * 0.8).clamp(-30.0, 30.0))
}
