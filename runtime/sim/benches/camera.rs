//! The simulator's camera pictures: one 640×480 frame of a drive and of a payload camera
//! (what `Sim::step` draws for each watched camera at `camera_fps`), against copying a
//! picture of that size once (the least any frame costs: it is sent as new bytes).
//!
//! `cargo bench -p mocu-sim --bench camera -- --warm-up-time 1 --measurement-time 3`

use criterion::{Criterion, criterion_group, criterion_main};
use mocu_sim::VehicleKind;
use mocu_sim::camera::{Lens, Pose, Renderer};
use std::hint::black_box;

fn frames(c: &mut Criterion) {
    let mut g = c.benchmark_group("camera_640x480");
    let picture = vec![90u8; 640 * 480 * 3];
    g.bench_function("baseline_copy", |b| b.iter(|| black_box(picture.clone())));
    for (name, lens) in [("drive", Lens::Drive), ("payload", Lens::Payload)] {
        let r = Renderer::new(640, 480, lens, VehicleKind::Usv);
        let mut heading = 0.0;
        g.bench_function(name, |b| {
            b.iter(|| {
                heading = (heading + 1.7) % 360.0;
                let pose = Pose { heading, pitch: 2.0, roll: 6.0, pan: 20.0, tilt: -2.0 };
                black_box(r.render(pose))
            })
        });
    }
    g.bench_function("scene_once", |b| {
        b.iter(|| black_box(Renderer::new(640, 480, Lens::Drive, VehicleKind::Usv)))
    });
    g.finish();
}

criterion_group!(benches, frames);
criterion_main!(benches);
