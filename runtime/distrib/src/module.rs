//! The `distrib` module: a profile's `[modules.distrib]` table, or what `mocu run` and
//! `mocu serve` make of `--listen`, `--connect` and `--operator`.

use crate::{Config, Distrib};
use mocu_host::{Level, Module, ModuleContext, ModuleSpec, Registry};
use std::time::Duration;

/// Registers the `distrib` kind.
pub fn register(registry: &mut Registry) {
    registry.register("distrib", |spec| {
        let (config, join) = config_from(spec)?;
        Ok(Box::new(DistribModule { config, join, running: None }) as Box<dyn Module>)
    });
}

pub(crate) fn names(spec: &ModuleSpec, key: &str) -> Result<Vec<String>, String> {
    match spec.settings.get(key) {
        None => Ok(Vec::new()),
        Some(toml::Value::Array(xs)) => xs
            .iter()
            .map(|x| {
                x.as_str().map(String::from).ok_or_else(|| format!("`{key}`: a list of strings"))
            })
            .collect(),
        Some(toml::Value::String(s)) => Ok(vec![s.clone()]),
        Some(_) => Err(format!("`{key}`: a list of strings")),
    }
}

/// Zenoh endpoints (`tcp/127.0.0.1:7447`, `tls/host:7447`), each parsed as Zenoh parses it
/// when the session opens: a malformed one is a settings error `mocu check` reports.
fn endpoints(spec: &ModuleSpec, key: &str) -> Result<Vec<String>, String> {
    let list = names(spec, key)?;
    for e in &list {
        if let Err(why) = e.parse::<zenoh::config::EndPoint>() {
            return Err(format!(
                "`{key}`: `{e}` is not a Zenoh endpoint such as tcp/127.0.0.1:7447 ({why})"
            ));
        }
    }
    Ok(list)
}

pub(crate) fn millis(spec: &ModuleSpec, key: &str, default: i64) -> Result<Duration, String> {
    let ms = spec.i64_or(key, default).map_err(|e| e.to_string())?;
    if !(1..=3_600_000).contains(&ms) {
        return Err(format!("`{key}` must be 1 to 3600000 ms"));
    }
    Ok(Duration::from_millis(ms as u64))
}

/// The settings of a `distrib` spec (docs/language.md, "Profiles").
pub fn config_from(spec: &ModuleSpec) -> Result<(Config, Duration), String> {
    let d = Config::default();
    let operator = spec.str_or("operator", "").map_err(|e| e.to_string())?;
    let site = spec.str_or("site", "").map_err(|e| e.to_string())?;
    let site = if !site.is_empty() {
        site
    } else if !operator.is_empty() {
        operator.clone()
    } else {
        d.site
    };
    let share = names(spec, "share")?;
    let config = Config {
        site,
        operator,
        listen: endpoints(spec, "listen")?,
        connect: endpoints(spec, "connect")?,
        control: crate::arbiter::settings_from(spec, &share)?,
        share,
        call_timeout: millis(spec, "call_timeout_ms", 10_000)?,
        lease: millis(spec, "lease_ms", 2_000)?,
        security: crate::security::from_spec(spec)?,
        streams: streams_from(spec)?,
    };
    Ok((config, millis(spec, "join_timeout_ms", 10_000)?))
}

/// `streams` (listener paths, `*` for any one name) and `stream_rate_hz`.
fn streams_from(spec: &ModuleSpec) -> Result<crate::streams::StreamChoice, String> {
    let rate = spec.f64_or("stream_rate_hz", 5.0).map_err(|e| e.to_string())?;
    if !(rate > 0.0 && rate <= 120.0) {
        return Err("`stream_rate_hz` must be more than 0 and at most 120".into());
    }
    Ok(crate::streams::StreamChoice::new(&names(spec, "streams")?, rate))
}

struct DistribModule {
    config: Config,
    join: Duration,
    running: Option<Distrib>,
}

impl Module for DistribModule {
    fn start(&mut self, ctx: &ModuleContext) -> Result<(), String> {
        let c = ctx.clone();
        let notify: crate::Notify =
            std::sync::Arc::new(move |text: &str| c.report(Level::Info, text));
        let d = Distrib::start_notifying(&ctx.ds, &self.config, Some(ctx.status), Some(notify))?;
        let _ = ctx.ds.set(ctx.status, "site", mocu_dataserver::Value::str(&self.config.site));
        ctx.report(
            Level::Info,
            format!(
                "site `{}`: listening on [{}], connecting to [{}], sharing [{}]",
                self.config.site,
                self.config.listen.join(", "),
                self.config.connect.join(", "),
                self.config.share.join(", ")
            ),
        );
        // A joiner starts with the world it joins: the first site's snapshot before the
        // rest of the OCU (bounded: an absent site is reported, not waited for).
        if !self.config.connect.is_empty() && !d.wait_snapshots(1, self.join) {
            ctx.report(
                Level::Warning,
                format!("no site answered within {} ms; going on", self.join.as_millis()),
            );
        }
        self.running = Some(d);
        Ok(())
    }

    fn stop(&mut self) {
        if let Some(d) = self.running.take() {
            d.stop();
        }
    }
}
