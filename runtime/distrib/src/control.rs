//! Control arbitration's rules (docs/distribution.md, "Control arbitration"): who holds a
//! vehicle, and what a request, a release, a takeover, a holder's answer, a command and a
//! holder's disappearance do. Pure state: no DataServer, no Zenoh, no clock (the arbiter,
//! `arbiter.rs`, keeps one [`Control`] per vehicle and turns its results into the world
//! model, call outcomes and timers).

/// What a takeover of a held vehicle does (per vehicle, from the profile).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Takeover {
    /// Granted at once: the holder loses control.
    #[default]
    Allowed,
    /// Refused while someone holds the vehicle.
    Denied,
    /// The holder is asked (an alert on their screen) and accepts or denies.
    Ask,
}

impl Takeover {
    pub fn parse(s: &str) -> Option<Takeover> {
        match s {
            "allowed" => Some(Takeover::Allowed),
            "denied" => Some(Takeover::Denied),
            "ask" => Some(Takeover::Ask),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Takeover::Allowed => "allowed",
            Takeover::Denied => "denied",
            Takeover::Ask => "ask",
        }
    }
}

/// Who calls: the operator and the site the call came from, as the calling process put
/// them in the call's payload (a layout cannot choose them).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Caller {
    pub operator: String,
    pub site: String,
}

impl Caller {
    pub fn new(operator: &str, site: &str) -> Caller {
        Caller { operator: operator.into(), site: site.into() }
    }
}

/// What a takeover did.
#[derive(Debug, PartialEq, Eq)]
pub enum Grant {
    /// The caller holds the vehicle now.
    Granted,
    /// The holder was asked; the answer (or the ask timeout) decides.
    Asked,
}

/// What the holder's answer to a takeover did.
#[derive(Debug, PartialEq, Eq)]
pub enum Answer {
    /// Control went to the asker.
    Handed(Caller),
    /// The holder kept it; the asker is told.
    Kept(Caller),
}

/// One vehicle's control.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Control {
    pub holder: Option<Caller>,
    /// An operator asking the holder for a takeover (policy [`Takeover::Ask`]).
    pub requested_by: Option<Caller>,
    pub takeover: Takeover,
    /// Whether a vehicle nobody holds takes commands from anyone (`free = "open"`) or
    /// only after a request (`free = "closed"`).
    pub open_when_free: bool,
    /// Set while the holder's site is gone: the epoch of the release timer that runs.
    pub gone: Option<u64>,
}

const NO_NAME: &str =
    "a call without an operator name cannot take control (start the OCU with --operator NAME)";

impl Control {
    pub fn new(takeover: Takeover, open_when_free: bool) -> Control {
        Control { takeover, open_when_free, ..Control::default() }
    }

    pub fn holder_name(&self) -> &str {
        self.holder.as_ref().map_or("", |h| h.operator.as_str())
    }

    fn holds(&self, who: &Caller) -> bool {
        self.holder.as_ref().is_some_and(|h| h.operator == who.operator)
    }

    /// Whether `who` may command the vehicle (call its methods, write its goals).
    pub fn command(&self, who: &Caller, vehicle: &str) -> Result<(), String> {
        match &self.holder {
            Some(_) if self.holds(who) => Ok(()),
            Some(h) => {
                Err(format!("{vehicle} is controlled by {}: request a takeover first", h.operator))
            }
            None if self.open_when_free => Ok(()),
            None => Err(format!("nobody controls {vehicle}: request control first")),
        }
    }

    /// Takes a free vehicle (or confirms the holder's own control, from whichever site).
    pub fn request(&mut self, who: &Caller, vehicle: &str) -> Result<(), String> {
        if who.operator.is_empty() {
            return Err(NO_NAME.into());
        }
        match &self.holder {
            Some(h) if h.operator != who.operator => Err(format!(
                "{vehicle} is controlled by {}: request a takeover instead",
                h.operator
            )),
            _ => {
                self.give(who.clone());
                Ok(())
            }
        }
    }

    /// Gives control back. A pending asker gets it (they asked for it); returns the new
    /// holder, if any.
    pub fn release(&mut self, who: &Caller, vehicle: &str) -> Result<Option<Caller>, String> {
        if !self.holds(who) {
            return Err(format!("{} does not control {vehicle}", name_of(who)));
        }
        Ok(self.hand_on())
    }

    /// Takes a vehicle someone else holds, as the vehicle's policy says.
    pub fn takeover(&mut self, who: &Caller, vehicle: &str) -> Result<Grant, String> {
        if who.operator.is_empty() {
            return Err(NO_NAME.into());
        }
        let Some(h) = self.holder.clone() else {
            self.give(who.clone());
            return Ok(Grant::Granted);
        };
        if h.operator == who.operator {
            self.give(who.clone());
            return Ok(Grant::Granted);
        }
        match self.takeover {
            Takeover::Allowed => {
                self.give(who.clone());
                Ok(Grant::Granted)
            }
            Takeover::Denied => {
                Err(format!("takeover of {vehicle} is denied: {} controls it", h.operator))
            }
            Takeover::Ask if self.gone.is_some() => Err(format!(
                "{} is not connected and cannot answer; {vehicle} is released when the \
                 timeout passes",
                h.operator
            )),
            Takeover::Ask => match &self.requested_by {
                Some(r) if r.operator != who.operator => {
                    Err(format!("{} is already asking {} for {vehicle}", r.operator, h.operator))
                }
                _ => {
                    self.requested_by = Some(who.clone());
                    Ok(Grant::Asked)
                }
            },
        }
    }

    /// The holder's answer to a pending takeover.
    pub fn answer(&mut self, who: &Caller, accept: bool, vehicle: &str) -> Result<Answer, String> {
        if !self.holds(who) {
            return Err(format!(
                "only {} can answer for {vehicle}",
                if self.holder_name().is_empty() { "the holder" } else { self.holder_name() }
            ));
        }
        let Some(asker) = self.requested_by.take() else {
            return Err(format!("nobody is asking for {vehicle}"));
        };
        if accept {
            self.give(asker.clone());
            Ok(Answer::Handed(asker))
        } else {
            Ok(Answer::Kept(asker))
        }
    }

    /// The ask timeout passed for `asker`: withdraws their request if it still stands.
    pub fn ask_expired(&mut self, asker: &Caller) -> bool {
        if self.requested_by.as_ref() == Some(asker) {
            self.requested_by = None;
            true
        } else {
            false
        }
    }

    /// A site disappeared: if it is the holder's, the release timer of `epoch` starts
    /// (returns true). A pending asker from it withdraws (returned second).
    pub fn site_gone(&mut self, site: &str, epoch: u64) -> (bool, Option<Caller>) {
        let asker = match &self.requested_by {
            Some(r) if r.site == site => self.requested_by.take(),
            _ => None,
        };
        let holder = self.holder.as_ref().is_some_and(|h| h.site == site) && self.gone.is_none();
        if holder {
            self.gone = Some(epoch);
        }
        (holder, asker)
    }

    /// A site returned: the holder's release timer, if it was its, no longer counts.
    pub fn site_back(&mut self, site: &str) {
        if self.holder.as_ref().is_some_and(|h| h.site == site) {
            self.gone = None;
        }
    }

    /// The release timer of `epoch` ran out: the holder, still gone, loses control.
    /// Returns the released holder and the new one (a pending asker), if that happened.
    pub fn release_timer(&mut self, epoch: u64) -> Option<(Caller, Option<Caller>)> {
        if self.gone != Some(epoch) {
            return None;
        }
        let old = self.holder.clone()?;
        Some((old, self.hand_on()))
    }

    fn give(&mut self, to: Caller) {
        if self.requested_by.as_ref().is_some_and(|r| r.operator == to.operator) {
            self.requested_by = None;
        }
        self.holder = Some(to);
        self.gone = None;
    }

    fn hand_on(&mut self) -> Option<Caller> {
        self.gone = None;
        self.holder = None;
        let next = self.requested_by.take()?;
        self.give(next.clone());
        Some(next)
    }
}

fn name_of(who: &Caller) -> &str {
    if who.operator.is_empty() { "a caller without an operator name" } else { &who.operator }
}

#[cfg(test)]
#[path = "control_tests.rs"]
mod tests;
