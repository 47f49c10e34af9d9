//! The arbitration rules, one vehicle at a time.

use super::*;

fn alice() -> Caller {
    Caller::new("alice", "alice")
}
fn bob() -> Caller {
    Caller::new("bob", "bob-ocu")
}
fn carol() -> Caller {
    Caller::new("carol", "carol")
}

fn held_by_alice(takeover: Takeover) -> Control {
    let mut c = Control::new(takeover, false);
    c.request(&alice(), "usv1").unwrap();
    c
}

#[test]
fn a_free_vehicle_goes_to_the_first_operator_who_requests_it_and_then_refuses_the_others() {
    let mut c = Control::new(Takeover::Allowed, false);
    assert_eq!(c.request(&alice(), "usv1"), Ok(()));
    assert_eq!(c.holder_name(), "alice");
    assert_eq!(
        c.request(&bob(), "usv1"),
        Err("usv1 is controlled by alice: request a takeover instead".into())
    );
    assert_eq!(c.request(&alice(), "usv1"), Ok(()), "asking again is harmless");
    assert_eq!(c.holder_name(), "alice");
}

#[test]
fn commands_from_an_operator_who_does_not_hold_the_vehicle_are_refused_with_the_holder_named() {
    let c = held_by_alice(Takeover::Allowed);
    assert_eq!(c.command(&alice(), "usv1"), Ok(()));
    // The holder is the operator, from any of their sites.
    assert_eq!(c.command(&Caller::new("alice", "alice-tablet"), "usv1"), Ok(()));
    assert_eq!(
        c.command(&bob(), "usv1"),
        Err("usv1 is controlled by alice: request a takeover first".into())
    );
}

#[test]
fn a_free_vehicle_takes_commands_from_anyone_only_when_its_policy_is_open() {
    let open = Control::new(Takeover::Allowed, true);
    assert_eq!(open.command(&bob(), "usv1"), Ok(()));
    let closed = Control::new(Takeover::Allowed, false);
    assert_eq!(
        closed.command(&bob(), "usv1"),
        Err("nobody controls usv1: request control first".into())
    );
}

#[test]
fn a_caller_without_an_operator_name_can_neither_request_nor_take_over() {
    let anon = Caller::new("", "python");
    let mut c = Control::new(Takeover::Allowed, true);
    assert!(c.request(&anon, "usv1").unwrap_err().contains("--operator NAME"));
    assert!(c.takeover(&anon, "usv1").unwrap_err().contains("--operator NAME"));
    assert_eq!(c.holder, None);
}

#[test]
fn only_the_holder_releases_and_then_the_vehicle_is_free() {
    let mut c = held_by_alice(Takeover::Allowed);
    assert_eq!(c.release(&bob(), "usv1"), Err("bob does not control usv1".into()));
    assert_eq!(c.release(&alice(), "usv1"), Ok(None));
    assert_eq!(c.holder, None);
    assert_eq!(c.release(&alice(), "usv1"), Err("alice does not control usv1".into()));
}

/// A policy, what bob's takeover returns, who holds after it, who is asking after it.
type Case = (Takeover, Result<Grant, String>, &'static str, Option<&'static str>);

#[test]
fn a_takeover_follows_the_vehicles_policy() {
    let cases: [Case; 3] = [
        (Takeover::Allowed, Ok(Grant::Granted), "bob", None),
        (
            Takeover::Denied,
            Err("takeover of usv1 is denied: alice controls it".into()),
            "alice",
            None,
        ),
        (Takeover::Ask, Ok(Grant::Asked), "alice", Some("bob")),
    ];
    for (policy, want, holder, asking) in cases {
        let mut c = held_by_alice(policy);
        assert_eq!(c.takeover(&bob(), "usv1"), want, "{policy:?}");
        assert_eq!(c.holder_name(), holder, "{policy:?}");
        assert_eq!(c.requested_by.as_ref().map(|r| r.operator.as_str()), asking, "{policy:?}");
    }
}

#[test]
fn a_takeover_of_a_free_vehicle_is_a_request_under_every_policy() {
    for policy in [Takeover::Allowed, Takeover::Denied, Takeover::Ask] {
        let mut c = Control::new(policy, false);
        assert_eq!(c.takeover(&bob(), "usv1"), Ok(Grant::Granted), "{policy:?}");
        assert_eq!(c.holder_name(), "bob");
    }
}

#[test]
fn the_holder_asked_for_a_takeover_hands_control_on_or_keeps_it() {
    let mut c = held_by_alice(Takeover::Ask);
    c.takeover(&bob(), "usv1").unwrap();
    assert_eq!(c.answer(&bob(), true, "usv1"), Err("only alice can answer for usv1".into()));
    assert_eq!(c.answer(&alice(), false, "usv1"), Ok(Answer::Kept(bob())));
    assert_eq!((c.holder_name(), c.requested_by.clone()), ("alice", None));
    assert_eq!(c.answer(&alice(), true, "usv1"), Err("nobody is asking for usv1".into()));
    c.takeover(&bob(), "usv1").unwrap();
    assert_eq!(c.answer(&alice(), true, "usv1"), Ok(Answer::Handed(bob())));
    assert_eq!((c.holder_name(), c.requested_by.clone()), ("bob", None));
}

#[test]
fn one_operator_asks_at_a_time_and_an_unanswered_ask_expires() {
    let mut c = held_by_alice(Takeover::Ask);
    c.takeover(&bob(), "usv1").unwrap();
    assert_eq!(c.takeover(&carol(), "usv1"), Err("bob is already asking alice for usv1".into()));
    assert!(!c.ask_expired(&carol()), "carol was not asking");
    assert!(c.ask_expired(&bob()));
    assert_eq!(c.requested_by, None);
    assert_eq!(c.takeover(&carol(), "usv1"), Ok(Grant::Asked));
}

#[test]
fn a_release_while_someone_asks_hands_control_to_the_asker() {
    let mut c = held_by_alice(Takeover::Ask);
    c.takeover(&bob(), "usv1").unwrap();
    assert_eq!(c.release(&alice(), "usv1"), Ok(Some(bob())));
    assert_eq!((c.holder_name(), c.requested_by.clone()), ("bob", None));
}

#[test]
fn a_holder_whose_site_is_gone_is_released_by_the_timer_of_that_departure_only() {
    let mut c = held_by_alice(Takeover::Allowed);
    assert_eq!(c.site_gone("bob-ocu", 1), (false, None), "not the holder's site");
    assert_eq!(c.site_gone("alice", 2), (true, None));
    c.site_back("alice");
    assert_eq!(c.release_timer(2), None, "alice came back before the timeout");
    assert_eq!(c.site_gone("alice", 3), (true, None));
    assert_eq!(c.release_timer(2), None, "an older departure's timer");
    assert_eq!(c.release_timer(3), Some((alice(), None)));
    assert_eq!(c.holder, None);
    assert_eq!(c.gone, None);
}

#[test]
fn a_gone_holder_cannot_be_asked_and_a_gone_asker_withdraws() {
    let mut c = held_by_alice(Takeover::Ask);
    c.takeover(&bob(), "usv1").unwrap();
    assert_eq!(c.site_gone("bob-ocu", 1), (false, Some(bob())));
    assert_eq!(c.requested_by, None);
    c.site_gone("alice", 2);
    assert!(c.takeover(&bob(), "usv1").unwrap_err().contains("alice is not connected"));
    // A holder who takes control again from another site stops the timer.
    c.request(&Caller::new("alice", "alice-tablet"), "usv1").unwrap();
    assert_eq!(c.release_timer(2), None);
    assert_eq!(c.holder_name(), "alice");
}

#[test]
fn policies_are_named_as_the_profile_writes_them() {
    for p in [Takeover::Allowed, Takeover::Denied, Takeover::Ask] {
        assert_eq!(Takeover::parse(p.name()), Some(p));
    }
    assert_eq!(Takeover::parse("maybe"), None);
}
