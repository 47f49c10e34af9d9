//! The mission protocol, and a route kept in step with the vehicle by deltas (paper §4: an
//! edit of a route is a change of the world-model route, and only what changed is sent).
//!
//! - `upload_route(route)` sends the whole route: MISSION_COUNT, then one MISSION_ITEM_INT per
//!   MISSION_REQUEST(_INT), until MISSION_ACK. Accepted, the link follows that route: the
//!   vehicle's `route` names it and `route_synced` says whether the vehicle holds it as it is.
//! - The watchdog (every 250 ms) compares the route with what the vehicle acknowledged. Each
//!   run of changed waypoints is sent as MISSION_WRITE_PARTIAL_LIST (start..=end) and the
//!   items the vehicle asks for: a waypoint dragged on the map costs one item, not the route.
//!   A change of the count (a waypoint inserted or deleted) is a whole upload: the protocol
//!   has no insert.
//! - A vehicle that refuses a partial write (any MISSION_ACK but ACCEPTED) or lets it time out
//!   gets the whole route at once, and whole uploads from then on.

use crate::commands::can_send;
use crate::link::{After, Link};
use crate::vehicle::Vehicle;
use mavlink::dialects::development::*;
use mocu_dataserver::{Call, CallOutcome, DataServer, Guid, Responder, Value};
use mocu_host::world;

pub(crate) type Item = MISSION_ITEM_INT_DATA;

/// The route the vehicle holds, as it acknowledged it.
pub(crate) struct Mission {
    pub route: Guid,
    pub items: Vec<Item>,
    /// Whether the vehicle takes partial writes (until it refuses one).
    pub partial: bool,
    /// A version of the route the vehicle refused: not sent again until the route changes.
    pub refused: Option<Vec<Item>>,
}

/// How an upload writes the mission.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Write {
    /// MISSION_COUNT and every item.
    Whole,
    /// MISSION_WRITE_PARTIAL_LIST and the items of `first..=last`.
    Partial,
}

/// An upload under way.
pub(crate) struct Upload {
    pub id: u64,
    pub route: Guid,
    /// The whole mission as it is once the upload is acknowledged.
    pub items: Vec<Item>,
    pub write: Write,
    /// The items the vehicle may ask for.
    pub first: u16,
    pub last: u16,
    /// MISSION_COUNT or MISSION_WRITE_PARTIAL_LIST: resent until the vehicle asks for an item.
    pub opening: MavMessage,
    pub attempts: u32,
    pub requested: bool,
    /// The `upload_route` call waiting for it (none for a delta the link sends by itself).
    pub responder: Option<Responder>,
}

/// Two items the vehicle would fly alike (the NaN yaw of ours compares unequal to itself).
fn same(a: &Item, b: &Item) -> bool {
    (a.x, a.y, a.z.to_bits(), a.command, a.frame) == (b.x, b.y, b.z.to_bits(), b.command, b.frame)
}

/// The runs of changed items, as inclusive index ranges, when the count is the same.
pub(crate) fn changed_runs(old: &[Item], new: &[Item]) -> Option<Vec<(u16, u16)>> {
    if old.len() != new.len() {
        return None;
    }
    let mut runs: Vec<(u16, u16)> = Vec::new();
    for (i, (a, b)) in old.iter().zip(new).enumerate() {
        if same(a, b) {
            continue;
        }
        let i = i as u16;
        match runs.last_mut() {
            Some(r) if r.1 + 1 == i => r.1 = i,
            _ => runs.push((i, i)),
        }
    }
    Some(runs)
}

/// The mission items of `route` for the vehicle `target`/`compid`: one NAV_WAYPOINT per
/// waypoint, at its `lat`/`lon` and `alt` (20 m when it has none).
pub(crate) fn route_items(
    ds: &DataServer,
    route: Guid,
    target: u8,
    compid: u8,
) -> Result<Vec<Item>, String> {
    match ds.info(route) {
        Ok(i) if &*i.kind == "route" => {}
        Ok(i) => return Err(format!("`{}` is a {}, not a route", i.name, i.kind)),
        Err(_) => return Err("no such route".into()),
    }
    let wps = world::route_waypoints(ds, route);
    if wps.len() > usize::from(u16::MAX) {
        return Err(format!("{} waypoints: a mission holds 65535 at most", wps.len()));
    }
    let mut items = Vec::with_capacity(wps.len());
    for (i, wp) in wps.iter().enumerate() {
        let Some((lat, lon)) = world::pair(ds, *wp, "lat", "lon") else {
            return Err(format!("waypoint {i} has no lat/lon"));
        };
        let alt = ds.try_get(*wp, "alt".into()).and_then(|a| a.as_f64()).unwrap_or(20.0);
        items.push(MISSION_ITEM_INT_DATA {
            param1: 0.0,
            param2: 2.0,
            param3: 0.0,
            param4: f32::NAN,
            x: (lat * 1e7).round() as i32,
            y: (lon * 1e7).round() as i32,
            z: alt as f32,
            seq: i as u16,
            command: MavCmd::MAV_CMD_NAV_WAYPOINT,
            target_system: target,
            target_component: compid,
            frame: MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT,
            current: 0,
            autocontinue: 1,
        });
    }
    Ok(items)
}

/// Starts an upload on `v` (nothing else under way); returns what to send first.
fn begin(
    v: &mut Vehicle,
    id: u64,
    route: Guid,
    items: Vec<Item>,
    partial: Option<(u16, u16)>,
    responder: Option<Responder>,
) -> MavMessage {
    let (target, compid) = (items[0].target_system, items[0].target_component);
    let (write, (first, last), opening) = match partial {
        Some((s, e)) => (
            Write::Partial,
            (s, e),
            MavMessage::MISSION_WRITE_PARTIAL_LIST(MISSION_WRITE_PARTIAL_LIST_DATA {
                start_index: s as i16,
                end_index: e as i16,
                target_system: target,
                target_component: compid,
            }),
        ),
        None => (
            Write::Whole,
            (0, items.len() as u16 - 1),
            MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
                count: items.len() as u16,
                target_system: target,
                target_component: compid,
            }),
        ),
    };
    v.upload = Some(Upload {
        id,
        route,
        items,
        write,
        first,
        last,
        opening: opening.clone(),
        attempts: 1,
        requested: false,
        responder,
    });
    opening
}

/// The next write that brings the vehicle's mission to `items`: a partial write of the first
/// changed run when the vehicle takes them and the count is the same, else the whole route;
/// `None` when nothing changed.
fn next_write(m: &Mission, items: &[Item]) -> Option<Option<(u16, u16)>> {
    match changed_runs(&m.items, items) {
        Some(runs) if runs.is_empty() => None,
        // start_index and end_index are int16 on the wire.
        Some(runs) if m.partial && runs[0].1 <= i16::MAX as u16 => Some(Some(runs[0])),
        _ => Some(None),
    }
}

impl Link {
    /// `upload_route(route)`: the whole route, then kept in step by deltas.
    pub(crate) fn upload(&self, c: Call) {
        let ds = &self.inner.ctx.ds;
        let Some(route) = c.args[0].as_guid() else {
            c.responder.fail("not a GUID");
            return;
        };
        let Some(sys) = self.inner.state.lock().by_guid.get(&c.object).copied() else {
            c.responder.reply(CallOutcome::NoSuchObject);
            return;
        };
        // Read the route with no lock of ours held; the target is checked again below.
        let (target, compid) = {
            let st = self.inner.state.lock();
            match st.vehicles.get(&sys).map(|v| (can_send(v), v.compid)) {
                Some((Ok(t), compid)) => (t, compid),
                Some((Err(why), _)) => {
                    drop(st);
                    c.responder.refuse(why);
                    return;
                }
                None => {
                    drop(st);
                    c.responder.reply(CallOutcome::NoSuchObject);
                    return;
                }
            }
        };
        let items = match route_items(ds, route, target, compid) {
            Ok(items) if items.is_empty() => {
                c.responder.refuse("the route has no waypoints");
                return;
            }
            Ok(items) => items,
            Err(why) => {
                c.responder.fail(why);
                return;
            }
        };
        let mut st = self.inner.state.lock();
        let id = st.next_id;
        st.next_id += 1;
        let Some(v) = st.vehicles.get_mut(&sys) else {
            drop(st);
            c.responder.reply(CallOutcome::NoSuchObject);
            return;
        };
        let refusal = if v.lost {
            Some(CallOutcome::Failed("link lost: no heartbeat from the vehicle".into()))
        } else if v.upload.is_some() {
            Some(CallOutcome::Refused("a route upload is already in progress".into()))
        } else {
            can_send(v).err().map(CallOutcome::Refused)
        };
        if let Some(o) = refusal {
            drop(st);
            c.responder.reply(o);
            return;
        }
        let addr = v.addr;
        let msg = begin(v, id, route, items, None, Some(c.responder));
        drop(st);
        self.send_to(addr, &msg);
        self.arm_retry(sys, id);
    }

    /// Sends what changed in the routes the vehicles hold (called by the watchdog).
    pub(crate) fn sync_routes(&self) {
        let ds = &self.inner.ctx.ds;
        let idle: Vec<(u32, Guid, u8, u8)> = {
            let st = self.inner.state.lock();
            st.vehicles
                .values()
                .filter(|v| v.upload.is_none() && !v.lost)
                .filter_map(|v| {
                    let m = v.mission.as_ref()?;
                    Some((v.sysid, m.route, can_send(v).ok()?, v.compid))
                })
                .collect()
        };
        for (sys, route, target, compid) in idle {
            let now = route_items(ds, route, target, compid);
            let mut st = self.inner.state.lock();
            let id = st.next_id;
            let Some(v) = st.vehicles.get_mut(&sys) else { continue };
            let Some(m) = v.mission.as_mut().filter(|m| m.route == route) else { continue };
            if v.upload.is_some() {
                continue;
            }
            let items = match now {
                Ok(items) if !items.is_empty() => items,
                // A route deleted: the vehicle keeps what it has, no longer followed.
                _ if ds.info(route).is_err() => {
                    v.mission = None;
                    let _ = ds.set(v.guid, "route_synced", Value::Bool(false));
                    continue;
                }
                // Emptied, or a waypoint being inserted (its position not yet written): the
                // vehicle keeps what it has until the route is one it can fly.
                _ => continue,
            };
            if m.refused.as_ref().is_some_and(|r| changed_runs(r, &items) == Some(vec![])) {
                continue;
            }
            m.refused = None;
            let Some(write) = next_write(m, &items) else { continue };
            st.next_id += 1;
            let v = st.vehicles.get_mut(&sys).expect("looked up above");
            let _ = ds.set(v.guid, "route_synced", Value::Bool(false));
            let addr = v.addr;
            let msg = begin(v, id, route, items, write, None);
            drop(st);
            self.send_to(addr, &msg);
            self.arm_retry(sys, id);
        }
    }

    /// An upload that ran out of attempts: a partial write falls back to the whole route
    /// (`Ok`: what to send, under the upload `id`); anything else ends (`Err`: the caller to
    /// tell, if any).
    pub(crate) fn upload_timed_out(
        &self,
        v: &mut Vehicle,
        id: u64,
    ) -> Result<MavMessage, Option<(Responder, CallOutcome)>> {
        let Some(up) = v.upload.take() else { return Err(None) };
        if up.write == Write::Partial {
            if let Some(m) = v.mission.as_mut() {
                m.partial = false;
            }
            return Ok(begin(v, id, up.route, up.items, None, None));
        }
        Err(self.upload_ended(v, up, CallOutcome::TimedOut))
    }

    /// A whole upload that failed or timed out: after an `upload_route` call the vehicle's
    /// mission is unknown (the caller, returned, is told); a delta's version is not sent again.
    fn upload_ended(
        &self,
        v: &mut Vehicle,
        up: Upload,
        outcome: CallOutcome,
    ) -> Option<(Responder, CallOutcome)> {
        match up.responder {
            Some(r) => {
                v.mission = None;
                Some((r, outcome))
            }
            None => {
                self.inner.ctx.report(
                    mocu_host::Level::Warning,
                    format!("mav{}: the edited route was not taken: {outcome:?}", v.sysid),
                );
                if let Some(m) = v.mission.as_mut() {
                    m.refused = Some(up.items);
                }
                None
            }
        }
    }

    /// The mission protocol's answers: items asked for, and the acknowledgement.
    pub(crate) fn answer(&self, v: &mut Vehicle, msg: &MavMessage, ids: &mut u64, a: &mut After) {
        match msg {
            // Legacy peers still send MISSION_REQUEST; the answer is MISSION_ITEM_INT either way.
            #[allow(deprecated)]
            MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA { seq, .. })
            | MavMessage::MISSION_REQUEST(MISSION_REQUEST_DATA { seq, .. }) => {
                let Some(up) = v.upload.as_mut() else { return };
                if !(up.first..=up.last).contains(seq) {
                    return;
                }
                let Some(item) = up.items.get(usize::from(*seq)) else { return };
                up.requested = true;
                up.attempts = 0;
                a.sends.push((v.addr, MavMessage::MISSION_ITEM_INT(item.clone())));
            }
            MavMessage::MISSION_ACK(ack) => {
                let Some(up) = v.upload.take() else { return };
                let accepted = ack.mavtype == MavMissionResult::MAV_MISSION_ACCEPTED;
                match (up.write, accepted) {
                    (Write::Whole, true) => {
                        let partial = v.mission.as_ref().is_none_or(|m| m.partial);
                        let n = up.items.len() as i64;
                        let m =
                            Mission { route: up.route, items: up.items, partial, refused: None };
                        v.mission = Some(m);
                        let ds = &self.inner.ctx.ds;
                        let _ = ds.set(v.guid, "route", Value::Guid(up.route));
                        let _ = ds.set(v.guid, "route_synced", Value::Bool(true));
                        if let Some(r) = up.responder {
                            a.replies.push((r, CallOutcome::Accepted(vec![Value::Int(n)])));
                        }
                    }
                    (Write::Partial, true) => {
                        let Some(m) = v.mission.as_mut() else { return };
                        let (f, l) = (usize::from(up.first), usize::from(up.last));
                        m.items[f..=l].clone_from_slice(&up.items[f..=l]);
                        // The next changed run of the same edit follows at once.
                        if let Some(write) = next_write(m, &up.items) {
                            let id = *ids;
                            *ids += 1;
                            let msg = begin(v, id, up.route, up.items, write, None);
                            a.sends.push((v.addr, msg));
                            a.timers.push((v.sysid, id));
                        } else {
                            let _ =
                                self.inner.ctx.ds.set(v.guid, "route_synced", Value::Bool(true));
                        }
                    }
                    (Write::Partial, false) => {
                        // Refused: this vehicle gets whole uploads from now on.
                        if let Some(m) = v.mission.as_mut() {
                            m.partial = false;
                        }
                        let id = *ids;
                        *ids += 1;
                        let msg = begin(v, id, up.route, up.items, None, None);
                        a.sends.push((v.addr, msg));
                        a.timers.push((v.sysid, id));
                    }
                    (Write::Whole, false) => {
                        let outcome = match ack.mavtype {
                            MavMissionResult::MAV_MISSION_ERROR
                            | MavMissionResult::MAV_MISSION_OPERATION_CANCELLED => {
                                CallOutcome::Failed(format!("{:?}", ack.mavtype))
                            }
                            other => CallOutcome::Refused(format!("{other:?}")),
                        };
                        a.replies.extend(self.upload_ended(v, up, outcome));
                    }
                }
            }
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn items(lats: &[i32]) -> Vec<Item> {
        let item = |(i, &x): (usize, &i32)| MISSION_ITEM_INT_DATA {
            param4: f32::NAN,
            x,
            y: -1_171_600_000,
            z: 20.0,
            seq: i as u16,
            command: MavCmd::MAV_CMD_NAV_WAYPOINT,
            frame: MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT,
            ..MISSION_ITEM_INT_DATA::default()
        };
        lats.iter().enumerate().map(item).collect()
    }

    #[test]
    fn the_changed_runs_are_the_waypoints_that_moved_and_a_count_change_has_none() {
        type Case = (&'static [i32], &'static [i32], Option<&'static [(u16, u16)]>);
        let cases: &[Case] = &[
            (&[1, 2, 3, 4], &[1, 2, 3, 4], Some(&[])),
            (&[1, 2, 3, 4], &[1, 2, 9, 4], Some(&[(2, 2)])),
            (&[1, 2, 3, 4], &[1, 8, 9, 4], Some(&[(1, 2)])),
            (&[1, 2, 3, 4], &[7, 2, 3, 9], Some(&[(0, 0), (3, 3)])),
            (&[1, 2, 3, 4], &[1, 2, 3], None),
            (&[1, 2, 3], &[1, 2, 5, 3], None),
        ];
        for (old, new, want) in cases {
            let got = changed_runs(&items(old), &items(new));
            assert_eq!(got.as_deref(), *want, "{old:?} -> {new:?}");
        }
    }
}
