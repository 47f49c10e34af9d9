//! A tracked UGV's manipulator (MOCU 3 paper, figure 2): three joints and a gripper, each
//! moving toward the goal the operator set at a limited rate, published under
//! `<vehicle>.manipulator` with the methods that move them.

use mocu_dataserver::{CallOutcome, DataServer, DsError, Guid, ObjectInfo, Value};
use mocu_host::world::{self, boolean, float, float_in, string};

/// The joints, their ranges (deg) and the pose the arm starts in.
pub(crate) const JOINTS: [(&str, f64, f64); 3] =
    [("shoulder", 0.0, 90.0), ("elbow", 0.0, 150.0), ("wrist", -90.0, 90.0)];
const START: [f64; 3] = [35.0, 70.0, -20.0];
/// Joint speed (deg/s) and gripper speed (fraction of full opening per second).
const JOINT_RATE: f64 = 30.0;
const GRIP_RATE: f64 = 0.8;

pub(crate) struct Manipulator {
    pub object: Guid,
    pub joints: [f64; 3],
    pub goals: [f64; 3],
    /// 0 closed .. 1 open.
    pub gripper: f64,
    pub gripper_goal: f64,
}

impl Manipulator {
    /// Publishes `<vehicle>.manipulator` with its joints and gripper.
    pub(crate) fn create(ds: &DataServer, vehicle: Guid) -> Result<Manipulator, DsError> {
        let object = ds.create_object(vehicle, ObjectInfo::new("manipulator", "manipulator"))?;
        let mut props = Vec::new();
        for (i, (name, lo, hi)) in JOINTS.iter().enumerate() {
            props.push((*name, Value::Float(START[i]), float_in("deg", *lo, *hi)));
        }
        props.extend([
            (
                "gripper",
                Value::Float(1.0),
                float_in("fraction", 0.0, 1.0).describe("0 closed, 1 open"),
            ),
            ("gripper_state", Value::str("open"), string().describe("open, closed or moving")),
            ("moving", Value::Bool(false), boolean()),
            ("reach", Value::Float(0.0), float("m").describe("gripper ahead of the shoulder")),
        ]);
        world::create_props(ds, object, props)?;
        let m =
            Manipulator { object, joints: START, goals: START, gripper: 1.0, gripper_goal: 1.0 };
        m.publish(ds);
        Ok(m)
    }

    /// Moves every joint and the gripper toward its goal for `dt` seconds.
    pub(crate) fn step(&mut self, dt: f64) {
        for (j, g) in self.joints.iter_mut().zip(self.goals) {
            *j += (g - *j).clamp(-JOINT_RATE * dt, JOINT_RATE * dt);
        }
        let d = self.gripper_goal - self.gripper;
        self.gripper += d.clamp(-GRIP_RATE * dt, GRIP_RATE * dt);
    }

    fn moving(&self) -> bool {
        self.joints.iter().zip(self.goals).any(|(j, g)| (j - g).abs() > 1e-6)
            || (self.gripper - self.gripper_goal).abs() > 1e-6
    }

    /// Where the gripper is ahead of the shoulder (m): links of 0.6 m and 0.5 m and a 0.2 m hand.
    fn reach(&self) -> f64 {
        let [s, e, w] = self.joints.map(f64::to_radians);
        0.6 * s.cos() + 0.5 * (s - e).cos() + 0.2 * (s - e + w).cos()
    }

    pub(crate) fn publish(&self, ds: &DataServer) {
        let g = self.object;
        for (i, (name, _, _)) in JOINTS.iter().enumerate() {
            let _ = ds.set(g, *name, Value::Float((self.joints[i] * 10.0).round() / 10.0));
        }
        let _ = ds.set(g, "gripper", Value::Float((self.gripper * 100.0).round() / 100.0));
        let state = if (self.gripper - self.gripper_goal).abs() > 1e-6 {
            "moving"
        } else if self.gripper < 0.05 {
            "closed"
        } else {
            "open"
        };
        let _ = ds.set(g, "gripper_state", Value::str(state));
        let _ = ds.set(g, "moving", Value::Bool(self.moving()));
        let _ = ds.set(g, "reach", Value::Float((self.reach() * 100.0).round() / 100.0));
    }

    /// `move_joints(shoulder, elbow, wrist)`: new goals, each within its range.
    pub(crate) fn move_joints(&mut self, args: &[Value]) -> CallOutcome {
        let mut goals = [0.0; 3];
        for (i, (name, lo, hi)) in JOINTS.iter().enumerate() {
            let v = args.get(i).and_then(Value::as_f64).unwrap_or(f64::NAN);
            if !(*lo..=*hi).contains(&v) {
                return CallOutcome::Refused(format!("{name} {v}° is outside {lo}..{hi}°"));
            }
            goals[i] = v;
        }
        self.goals = goals;
        CallOutcome::Accepted(vec![])
    }

    /// `grip(close)`: closes or opens the gripper.
    pub(crate) fn grip(&mut self, close: bool) -> CallOutcome {
        self.gripper_goal = if close { 0.0 } else { 1.0 };
        CallOutcome::Accepted(vec![])
    }

    /// `stow()`: folds the arm (every joint to 0) with the gripper closed.
    pub(crate) fn stow(&mut self) -> CallOutcome {
        self.goals = [0.0; 3];
        self.gripper_goal = 0.0;
        CallOutcome::Accepted(vec![])
    }
}
