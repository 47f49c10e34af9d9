//! `/location/<object path>` (`foxglove.LocationFix`): an object's `lat`, `lon` and `alt` as
//! one fix, for Foxglove's Map panel. The positions themselves are recorded like any number
//! (`/world/values`, which replay reads); the fixes are a view of them, written at most once
//! every [`FIX_EVERY_NS`] of trial time per object, and always with the object's last
//! position: a change that comes sooner waits, and is written once that time has passed
//! ([`Translator::due_fixes`], after each batch the recorder takes), before the object is
//! deleted, or when the recording ends. A fleet at 100 Hz thus costs ten fixes a second a
//! vehicle, not three hundred (one per coordinate changed).

use super::{Translator, timestamp};
use crate::file::Dynamic;
use crate::json;
use mocu_dataserver::Guid;

/// The least time between two fixes of one object (100 ms: ten a second).
pub(crate) const FIX_EVERY_NS: u64 = 100_000_000;

/// One object's position as last changed, and its fixes.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Place {
    /// `lat`, `lon`, `alt` as last changed.
    coords: [Option<f64>; 3],
    /// The number and time of the last change of one of them.
    seq: u64,
    t: u64,
    /// No fix before this time (the last fix's time plus [`FIX_EVERY_NS`]).
    next: u64,
    /// A change not in a fix yet.
    waiting: bool,
}

impl Place {
    /// Latitude and longitude, once both are known and finite.
    fn fix(&self) -> Option<(f64, f64, f64)> {
        let [Some(lat), Some(lon), alt] = self.coords else { return None };
        let alt = alt.filter(|a| a.is_finite()).unwrap_or(0.0);
        (lat.is_finite() && lon.is_finite()).then_some((lat, lon, alt))
    }
}

impl Translator {
    /// Coordinate `i` (`lat`, `lon`, `alt`) of `object` took `v` (`None`: not a number) in change `seq` at `t`: a
    /// fix now if the object's last one is old enough, else when it is
    /// ([`Translator::due_fixes`]).
    pub(super) fn place(
        &mut self,
        object: Guid,
        i: usize,
        v: Option<f64>,
        seq: u64,
        t: u64,
    ) -> Result<(), String> {
        let p = self.places.entry(object).or_default();
        p.coords[i] = v;
        (p.seq, p.t) = (seq, t);
        if p.fix().is_none() {
            return Ok(());
        }
        if t >= p.next {
            return self.write_fix(object);
        }
        if !p.waiting {
            p.waiting = true;
            self.waiting_fixes.push(object);
        }
        Ok(())
    }

    /// Writes the fixes that waited and whose time has come by `now` (every one that
    /// waited, with `now` = `u64::MAX`).
    pub(super) fn due_fixes(&mut self, now: u64) -> Result<(), String> {
        let places = &self.places;
        let (due, later): (Vec<Guid>, Vec<Guid>) = std::mem::take(&mut self.waiting_fixes)
            .into_iter()
            .filter(|object| places.get(object).is_some_and(|p| p.waiting))
            .partition(|object| places[object].next <= now);
        self.waiting_fixes = later;
        for object in due {
            // Listed again if it waited again after a fix written at once: written once.
            if self.places.get(&object).is_some_and(|p| p.waiting) {
                self.write_fix(object)?;
            }
        }
        Ok(())
    }

    /// The fix of `object`'s position as last changed, stamped with that change.
    pub(super) fn write_fix(&mut self, object: Guid) -> Result<(), String> {
        let Some(p) = self.places.get_mut(&object) else { return Ok(()) };
        // No longer waiting, even without a fix to write: a later change waits afresh.
        p.waiting = false;
        let Some((lat, lon, alt)) = p.fix() else { return Ok(()) };
        p.next = p.t.saturating_add(FIX_EVERY_NS);
        let (seq, t) = (p.seq, p.t);
        let path = self.world.path(object);
        let ch = self.out.dynamic(Dynamic::Location, &format!("/location/{path}"))?;
        let b = &mut self.buf;
        b.clear();
        timestamp(b, t);
        b.extend_from_slice(b",\"frame_id\":");
        json::string(b, &path);
        b.extend_from_slice(b",\"latitude\":");
        json::float(b, lat);
        b.extend_from_slice(b",\"longitude\":");
        json::float(b, lon);
        b.extend_from_slice(b",\"altitude\":");
        json::float(b, alt);
        b.extend_from_slice(
            b",\"position_covariance\":[0,0,0,0,0,0,0,0,0],\"position_covariance_type\":0}",
        );
        self.out.write(ch, seq, t, &self.buf)?;
        Ok(())
    }

    /// `object` is deleted (itself or an object above it): its waiting fix is written first.
    pub(super) fn forget_place(&mut self, object: Guid) -> Result<(), String> {
        if self.places.get(&object).is_some_and(|p| p.waiting) {
            self.write_fix(object)?;
        }
        self.places.remove(&object);
        Ok(())
    }
}
