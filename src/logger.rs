//! The logger behind the `log` facade, so that wgpu, naga and winit (and our own `log`
//! lines) reach the terminal. `RUST_LOG` chooses what is shown, in env_logger's syntax: a
//! level (`info`), `target=level` pairs, or both, comma-separated (`warn,wgpu_core=info`);
//! the longest matching target prefix wins. The default is `warn`.
//!
//! Not env_logger: it turns on the `std` feature of `log`, which would give every crate of
//! the workspace that logs two builds (one with mocu, one without).

use log::{LevelFilter, Log, Metadata, Record};
use std::io::Write;

/// What `RUST_LOG` asked for: a default level and per-target levels.
#[derive(Debug, PartialEq)]
pub struct Filter {
    default: LevelFilter,
    targets: Vec<(String, LevelFilter)>,
}

impl Filter {
    /// Parses `RUST_LOG`; unknown parts are ignored (a logger must not stop the OCU).
    pub fn parse(spec: &str) -> Filter {
        let mut f = Filter { default: LevelFilter::Warn, targets: Vec::new() };
        for part in spec.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            match part.split_once('=') {
                Some((target, level)) => {
                    if let Ok(l) = level.trim().parse() {
                        f.targets.push((target.trim().to_string(), l));
                    }
                }
                None => match part.parse() {
                    Ok(l) => f.default = l,
                    // A bare target means everything from it.
                    Err(_) => f.targets.push((part.to_string(), LevelFilter::Trace)),
                },
            }
        }
        // Longest prefix first, so the first match is the most specific.
        f.targets.sort_by_key(|(t, _)| std::cmp::Reverse(t.len()));
        f
    }

    /// The level shown for `target`.
    pub fn level_for(&self, target: &str) -> LevelFilter {
        self.targets
            .iter()
            .find(|(t, _)| {
                target.strip_prefix(t.as_str()).is_some_and(|r| r.is_empty() || r.starts_with("::"))
            })
            .map_or(self.default, |(_, l)| *l)
    }

    /// The most verbose level any target may log at.
    fn max(&self) -> LevelFilter {
        self.targets.iter().map(|(_, l)| *l).fold(self.default, std::cmp::max)
    }
}

struct Stderr(Filter);

impl Log for Stderr {
    fn enabled(&self, m: &Metadata<'_>) -> bool {
        m.level() <= self.0.level_for(m.target())
    }

    fn log(&self, r: &Record<'_>) {
        if self.enabled(r.metadata()) {
            let level = r.level().as_str().to_lowercase();
            let _ = writeln!(std::io::stderr().lock(), "{level}: {}: {}", r.target(), r.args());
        }
    }

    fn flush(&self) {
        let _ = std::io::stderr().flush();
    }
}

/// Installs the logger (once; later calls do nothing).
pub fn init() {
    let filter = Filter::parse(&std::env::var("RUST_LOG").unwrap_or_default());
    let max = filter.max();
    if log::set_logger(Box::leak(Box::new(Stderr(filter)))).is_ok() {
        log::set_max_level(max);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rust_log_chooses_levels_per_target_with_warn_by_default() {
        let cases: &[(&str, &str, LevelFilter)] = &[
            ("", "wgpu_core::device", LevelFilter::Warn),
            ("info", "naga", LevelFilter::Info),
            ("warn,wgpu_core=info", "wgpu_core::instance", LevelFilter::Info),
            ("warn,wgpu_core=info", "wgpu_hal", LevelFilter::Warn),
            ("wgpu=debug,wgpu_core=error", "wgpu_core", LevelFilter::Error),
            ("wgpu=debug,wgpu_core=error", "wgpu::backend", LevelFilter::Debug),
            ("off", "winit", LevelFilter::Off),
            ("mocu", "mocu::run", LevelFilter::Trace),
            ("nonsense=loud,error", "mocu", LevelFilter::Error),
        ];
        for (spec, target, want) in cases {
            assert_eq!(Filter::parse(spec).level_for(target), *want, "RUST_LOG={spec} {target}");
        }
    }

    #[test]
    fn the_facade_is_opened_as_far_as_the_most_verbose_target() {
        assert_eq!(Filter::parse("warn,naga=trace").max(), LevelFilter::Trace);
        assert_eq!(Filter::parse("").max(), LevelFilter::Warn);
    }
}
