//! Seeking to the middle of a one-hour recording (issue 18: ≤ 200 ms): a generated hour of
//! four vehicles with 20 properties each at 20 Hz (5.8 million changes, keyframes every
//! 10 s, LZ4 chunks of 1 MiB, the format of docs/recording.md). `seek_middle_*` open the
//! file (summary and chunk index) and seek to 30:00 (on a keyframe) or to 29:59.95 (9.95 s of
//! changes after the last keyframe); the baseline `open` only opens it.
//! Run: `cargo bench -p mocu-replay --bench seek -- --warm-up-time 1 --measurement-time 3`.

#[path = "../tests/support/mod.rs"]
mod support;

use criterion::{Criterion, criterion_group, criterion_main};
use mocu_replay::Player;
use support::{Synthetic, write};

const HOUR: Synthetic =
    Synthetic { seconds: 3600, vehicles: 4, props: 20, hz: 20, keyframe_secs: 10, batch_steps: 2 };

fn seek(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("hour.mcap");
    let t = std::time::Instant::now();
    write(&path, HOUR);
    let size = std::fs::metadata(&path).unwrap().len();
    eprintln!("generated an hour: {} MB in {:.1} s", size / 1_000_000, t.elapsed().as_secs_f64());
    let mut g = c.benchmark_group("seek_hour");
    g.sample_size(10);
    g.bench_function("open", |b| b.iter(|| Player::open(&path).unwrap()));
    // At 30:00 a keyframe falls: the best case. At 29:59.95 the last keyframe is 9.95 s
    // back, 15,920 changes before the time: the worst case of a seek into the middle.
    for (name, secs) in [("seek_middle_on_keyframe", 1800.0), ("seek_middle_worst", 1799.95)] {
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut p = Player::open(&path).unwrap();
                let t = p.at_secs(secs);
                p.seek(t).unwrap();
                p
            })
        });
    }
    g.finish();
    // The answer checked once: the world at 30:00 is step 36,000's.
    let mut p = Player::open(&path).unwrap();
    p.seek(p.at_secs(1800.0)).unwrap();
    let ds = p.ds();
    let v = ds.resolve(&["vehicles", "usv3"]).unwrap();
    assert_eq!(
        ds.try_get(v, "p19".into()).and_then(|x| x.as_f64()),
        Some(support::value(36_000, 19))
    );
}

criterion_group!(benches, seek);
criterion_main!(benches);
