//! Synthetic cameras: what a camera on a simulated vehicle would see of a simple world — a
//! sky, a sea or terrain, and a skyline of hills, buildings and buoys fixed in the world —
//! so that the picture moves with the vehicle (the horizon tilts with roll and rises and
//! falls with pitch, the skyline slides with heading) and a drive/payload swap is visible.
//!
//! A drive camera is wide (60°) and in colour, with a heading scale along its horizon; a payload
//! camera is narrow (20°, a zoom), monochrome (an EO sensor), pointed by its own pan and tilt,
//! with a pan/tilt indicator near its bottom and a fine cross in its middle.
//!
//! Cost: everything that does not depend on the pose (the sky and ground shades by distance
//! from the horizon, the ground texture, the skyline by azimuth) is drawn once per renderer;
//! a frame is two slice copies per row plus a short column per skyline pixel column and a few
//! ticks, no per-pixel arithmetic over the whole picture (`benches/camera.rs` in this crate).

use crate::vehicle::VehicleKind;

/// Which camera of a vehicle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lens {
    /// Forward, fixed to the vehicle, wide, in colour, with a heading scale.
    Drive,
    /// On a pan/tilt head, narrow, monochrome.
    Payload,
}

impl Lens {
    /// Horizontal field of view, degrees.
    pub fn fov(self) -> f64 {
        match self {
            Lens::Drive => 60.0,
            Lens::Payload => 20.0,
        }
    }
}

/// Where the camera looks: the vehicle's attitude and the head's pan and tilt (degrees;
/// pan to the right of the bow, tilt up).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pose {
    pub heading: f64,
    pub pitch: f64,
    pub roll: f64,
    pub pan: f64,
    pub tilt: f64,
}

/// Azimuth bins of the skyline: a quarter degree each.
const BINS: usize = 1440;

/// One camera's renderer: its size, lens and scene, and what it drew once.
pub struct Renderer {
    w: usize,
    h: usize,
    lens: Lens,
    /// Pixels per degree (the same both ways: square pixels).
    ppd: f64,
    /// `2h` rows of `2w` pixels: row `d` is the sky `h - d` rows above the horizon.
    sky: Vec<u8>,
    /// `2h` rows of `2w` pixels: row `d` is the ground `d` rows below the horizon; twice the
    /// width so that a row slid by the heading is one copy.
    ground: Vec<u8>,
    /// Elevation of the skyline (degrees) and its colour, per azimuth bin.
    skyline: Vec<(f32, [u8; 3])>,
}

impl Renderer {
    pub fn new(w: u32, h: u32, lens: Lens, kind: VehicleKind) -> Renderer {
        let (w, h) = (w.max(1) as usize, h.max(1) as usize);
        let ppd = w as f64 / lens.fov();
        let mono = lens == Lens::Payload;
        let paint = |c: [u8; 3]| if mono { grey(c) } else { c };
        let (sky_top, sky_low) = ([38, 92, 160], [168, 196, 222]);
        let (near, far) = match kind {
            VehicleKind::Usv => ([18, 52, 78], [64, 104, 130]),
            VehicleKind::Ugv => ([86, 70, 44], [120, 118, 92]),
            VehicleKind::Uav => ([54, 84, 48], [118, 132, 118]),
        };
        let (rows, cols) = (2 * h, 2 * w);
        let mut sky = Vec::with_capacity(rows * cols * 3);
        let mut ground = Vec::with_capacity(rows * cols * 3);
        for d in 0..rows {
            // Sky: hazy at the horizon, deep blue 30° above it.
            let up = ((h as f64 - d as f64) / (30.0 * ppd)).clamp(0.0, 1.0);
            let s = paint(mix(sky_low, sky_top, up.sqrt()));
            for _ in 0..cols {
                sky.extend_from_slice(&s);
            }
            // Ground: far shades at the horizon, near ones 25° below it; a texture of
            // streaks (waves, furrows) in perspective: bands of equal distance, thin and
            // short far away, thick and long near.
            let down = (d as f64 / (25.0 * ppd)).clamp(0.0, 1.0);
            let base = mix(far, near, down.powf(0.6));
            let band = (8.0 * h as f64 / (d as f64 + 1.0)).floor() as u64;
            let seg_w = 2.0 + d as f64 * 0.3;
            for x in 0..cols {
                let seg = (x as f64 / seg_w).floor() as u64;
                let streak = hash(band.wrapping_mul(7919) ^ seg.wrapping_mul(104_729)) % 7;
                let c = if streak == 0 { lighten(base, 14) } else { base };
                ground.extend_from_slice(&paint(c));
            }
        }
        let skyline = skyline(kind).into_iter().map(|(e, c)| (e, paint(c))).collect();
        Renderer { w, h, lens, ppd, sky, ground, skyline }
    }

    /// One RGB8 frame, `w`×`h`, row by row.
    pub fn render(&self, pose: Pose) -> Vec<u8> {
        let (w, h) = (self.w, self.h);
        let mut px = Vec::with_capacity(w * h * 3);
        let look = pose.heading + pose.pan;
        let elevation = pose.pitch + pose.tilt;
        // The horizon at the middle column, and its slope (rolling right tilts it left).
        let mid = h as f64 / 2.0 + elevation * self.ppd;
        let slope = -pose.roll.to_radians().tan().clamp(-2.0, 2.0);
        let cx = w as f64 / 2.0;
        let slide = ((look.rem_euclid(360.0) * self.ppd).round() as usize) % w;
        let sky_row = |d: usize| &self.sky[d * 2 * w * 3..][..w * 3];
        let ground_row = |d: usize| &self.ground[(d * 2 * w + slide) * 3..][..w * 3];
        let far = |v: f64| v.clamp(0.0, (2 * h - 1) as f64) as usize;
        for y in 0..h {
            let yc = y as f64 + 0.5;
            // The horizon at column x is `mid + slope * (x - cx)`; this row is sky where
            // `yc` is above it. `split`: the first column on the other side.
            let split = if slope == 0.0 {
                if yc < mid { w } else { 0 }
            } else {
                ((yc - mid) / slope + cx).clamp(0.0, w as f64).round() as usize
            };
            let depth = yc - mid;
            let s = sky_row(far(h as f64 + depth));
            let g = ground_row(far(depth));
            // Rolled left (`slope` > 0) the sky is right of the split, else left of it.
            let (a, b) = if slope <= 0.0 { (s, g) } else { (g, s) };
            px.extend_from_slice(&a[..split * 3]);
            px.extend_from_slice(&b[split * 3..]);
        }
        self.draw_skyline(&mut px, look, mid, slope);
        match self.lens {
            Lens::Drive => self.draw_tape(&mut px, look, mid, slope),
            Lens::Payload => self.draw_head(&mut px, pose.pan, pose.tilt),
        }
        px
    }

    /// The skyline: a column per pixel column, standing on the horizon.
    fn draw_skyline(&self, px: &mut [u8], look: f64, mid: f64, slope: f64) {
        let (w, h) = (self.w, self.h);
        let fov = self.lens.fov();
        for x in 0..w {
            let az = look + ((x as f64 + 0.5) / w as f64 - 0.5) * fov;
            let bin = ((az.rem_euclid(360.0)) * (BINS as f64 / 360.0)) as usize % BINS;
            let (elev, colour) = self.skyline[bin];
            if elev <= 0.0 {
                continue;
            }
            let base = mid + slope * (x as f64 + 0.5 - w as f64 / 2.0);
            let top = (base - elev as f64 * self.ppd).round().max(0.0) as usize;
            let bottom = (base.round().max(0.0) as usize).min(h);
            for y in top..bottom {
                let i = (y * w + x) * 3;
                px[i..i + 3].copy_from_slice(&colour);
            }
        }
    }

    /// The heading scale of a drive camera, along the horizon (it tilts and rises with it,
    /// as an EO sight's does): a tick every 10° standing on the horizon, the heading every
    /// 30° in digits above it, north in red.
    fn draw_tape(&self, px: &mut [u8], look: f64, mid: f64, slope: f64) {
        let (w, h) = (self.w, self.h);
        let unit = (h / 240).max(1);
        let fov = self.lens.fov();
        let first = ((look - fov / 2.0) / 10.0).ceil() as i64;
        let last = ((look + fov / 2.0) / 10.0).floor() as i64;
        for k in first..=last {
            let deg = (k * 10).rem_euclid(360);
            let x = ((k as f64 * 10.0 - look) / fov + 0.5) * w as f64;
            let base = (mid + slope * (x - w as f64 / 2.0)).round() as i64;
            let x = x.round() as i64;
            let major = deg % 30 == 0;
            let colour = if deg == 0 { [239, 68, 68] } else { [240, 244, 248] };
            let len = if major { 8 * unit } else { 4 * unit };
            fill(px, w, h, x - unit as i64 / 2, base - len as i64, unit, len, colour);
            if major {
                let text = format!("{:03}", deg);
                let tw = (text.len() * 4 - 1) * unit;
                let y = base - (len + 7 * unit) as i64;
                digits(px, w, h, x - tw as i64 / 2, y, unit, &text, colour);
            }
        }
    }

    /// The pan/tilt head's indicator (a box at the bottom, an eighth of the height up, with a
    /// dot where the head points: pan ±180° across, tilt -90..+30° down it) and a fine cross
    /// in the middle.
    fn draw_head(&self, px: &mut [u8], pan: f64, tilt: f64) {
        let (w, h) = (self.w, self.h);
        let unit = (h / 160).max(1);
        let (bw, bh) = (40 * unit, 20 * unit);
        if bw * 3 > w || bh * 3 > h {
            return;
        }
        let (x0, y0) = (((w - bw) / 2) as i64, (h - bh - h * 2 / 15) as i64);
        let frame = [210, 210, 210];
        fill(px, w, h, x0, y0, bw, unit, frame);
        fill(px, w, h, x0, y0 + (bh - unit) as i64, bw, unit, frame);
        fill(px, w, h, x0, y0, unit, bh, frame);
        fill(px, w, h, x0 + (bw - unit) as i64, y0, unit, bh, frame);
        // The bow: pan 0.
        fill(px, w, h, x0 + (bw / 2) as i64, y0, unit, bh, [120, 120, 120]);
        let dx = ((pan.clamp(-180.0, 180.0) + 180.0) / 360.0 * (bw - 3 * unit) as f64) as i64;
        let dy = ((30.0 - tilt.clamp(-90.0, 30.0)) / 120.0 * (bh - 3 * unit) as f64) as i64;
        fill(px, w, h, x0 + unit as i64 + dx, y0 + unit as i64 + dy, unit, unit, [255, 255, 255]);
        fill(px, w, h, x0 + dx, y0 + dy + unit as i64, 3 * unit, unit, [255, 255, 255]);
        fill(px, w, h, x0 + unit as i64 + dx, y0 + dy, unit, 3 * unit, [255, 255, 255]);
        // The cross: four arms with a gap in the middle.
        let (cx, cy) = ((w / 2) as i64, (h / 2) as i64);
        let (gap, arm) = (4 * unit as i64, 10 * unit);
        let white = [240, 240, 240];
        fill(px, w, h, cx - gap - arm as i64, cy, arm, unit, white);
        fill(px, w, h, cx + gap, cy, arm, unit, white);
        fill(px, w, h, cx, cy - gap - arm as i64, unit, arm, white);
        fill(px, w, h, cx, cy + gap, unit, arm, white);
    }
}

/// Fills a rectangle, clipped to the picture.
#[allow(clippy::too_many_arguments)]
fn fill(px: &mut [u8], w: usize, h: usize, x: i64, y: i64, rw: usize, rh: usize, c: [u8; 3]) {
    let (x0, y0) = (x.max(0) as usize, y.max(0) as usize);
    let x1 = ((x + rw as i64).max(0) as usize).min(w);
    let y1 = ((y + rh as i64).max(0) as usize).min(h);
    for yy in y0..y1 {
        for xx in x0..x1 {
            let i = (yy * w + xx) * 3;
            px[i..i + 3].copy_from_slice(&c);
        }
    }
}

/// Digits in a 3×5 font, each dot `unit` pixels.
#[allow(clippy::too_many_arguments)]
fn digits(px: &mut [u8], w: usize, h: usize, x: i64, y: i64, unit: usize, s: &str, c: [u8; 3]) {
    const FONT: [u16; 10] =
        [0o75557, 0o26227, 0o71747, 0o71717, 0o55711, 0o74717, 0o74757, 0o71111, 0o75757, 0o75717];
    for (i, ch) in s.chars().enumerate() {
        let Some(d) = ch.to_digit(10) else { continue };
        let glyph = FONT[d as usize];
        for row in 0..5 {
            let bits = (glyph >> (3 * (4 - row))) & 0o7;
            for col in 0..3 {
                if bits & (4 >> col) != 0 {
                    let gx = x + ((i * 4 + col) * unit) as i64;
                    let gy = y + (row * unit) as i64;
                    fill(px, w, h, gx, gy, unit, unit, c);
                }
            }
        }
    }
}

/// What the world shows at each azimuth: elevation (degrees) and colour. Fixed in the world,
/// the same for every vehicle of a type, so that turning slides it across the picture.
fn skyline(kind: VehicleKind) -> Vec<(f32, [u8; 3])> {
    let mut out = vec![(0.0f32, [0u8; 3]); BINS];
    let deg = |a: f64| ((a.rem_euclid(360.0)) * BINS as f64 / 360.0) as usize % BINS;
    let mut span = |from: f64, to: f64, f: &dyn Fn(f64) -> (f32, [u8; 3])| {
        let (a, b) = (deg(from), deg(to));
        let n = (b + BINS - a) % BINS;
        for k in 0..=n {
            let t = k as f64 / n.max(1) as f64;
            let (e, c) = f(t);
            let slot = &mut out[(a + k) % BINS];
            if e > slot.0 {
                *slot = (e, c);
            }
        }
    };
    let hill = |peak: f64, lumps: u64, colour: [u8; 3]| {
        move |t: f64| {
            let shape = (t * std::f64::consts::PI).sin().powf(0.7);
            let ripple = 0.8 + 0.2 * ((t * lumps as f64 * 6.3).sin() * 0.5 + 0.5);
            ((peak * shape * ripple) as f32, colour)
        }
    };
    match kind {
        VehicleKind::Usv => {
            // A headland, the harbour front (blocks of buildings), an island, the buoys of a
            // channel (red to port, green to starboard of the way in).
            span(20.0, 110.0, &hill(4.0, 3, [70, 92, 70]));
            span(190.0, 262.0, &|t| {
                let block = (t * 24.0) as u64;
                let e = 1.0 + (hash(block) % 10) as f64 * 0.25;
                (e as f32, if block.is_multiple_of(3) { [150, 140, 128] } else { [118, 112, 108] })
            });
            span(300.0, 336.0, &hill(1.6, 2, [86, 104, 80]));
            for (az, c) in [(150.0, [220, 50, 50]), (160.0, [40, 170, 70]), (172.0, [220, 50, 50])]
            {
                span(az, az + 0.75, &|_| (0.7, c));
            }
        }
        VehicleKind::Ugv | VehicleKind::Uav => {
            // Ridges all round, a tree line in front of them, a mast to the north.
            span(0.0, 130.0, &hill(3.0, 4, [92, 104, 120]));
            span(110.0, 250.0, &hill(2.0, 5, [104, 112, 126]));
            span(230.0, 359.9, &hill(3.6, 3, [88, 100, 118]));
            span(40.0, 200.0, &|t| {
                let e = 0.5 + (hash((t * 90.0) as u64) % 5) as f64 * 0.08;
                (e as f32, [46, 72, 40])
            });
            span(359.6, 0.4, &|_| (5.0, [200, 200, 200]));
        }
    }
    out
}

fn mix(a: [u8; 3], b: [u8; 3], t: f64) -> [u8; 3] {
    let m = |x: u8, y: u8| (x as f64 + (y as f64 - x as f64) * t).round() as u8;
    [m(a[0], b[0]), m(a[1], b[1]), m(a[2], b[2])]
}

fn lighten(c: [u8; 3], by: u8) -> [u8; 3] {
    c.map(|v| v.saturating_add(by))
}

/// Luma (BT.601) of a colour, as grey.
fn grey(c: [u8; 3]) -> [u8; 3] {
    let y = (c[0] as u32 * 299 + c[1] as u32 * 587 + c[2] as u32 * 114) / 1000;
    [y as u8; 3]
}

/// A fixed hash (SplitMix64's finaliser): the same scene on every machine.
fn hash(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(px: &[u8], w: usize, x: usize, y: usize) -> [u8; 3] {
        let i = (y * w + x) * 3;
        [px[i], px[i + 1], px[i + 2]]
    }

    /// The first row, from the top, at column `x` that is not sky blue-ish (the horizon or
    /// the skyline).
    fn horizon(px: &[u8], w: usize, h: usize, x: usize) -> usize {
        (h / 4..h).find(|&y| at(px, w, x, y)[2] < 150).unwrap_or(h)
    }

    #[test]
    fn the_horizon_rises_with_a_pitch_down_and_tilts_with_roll() {
        let r = Renderer::new(320, 240, Lens::Drive, VehicleKind::Usv);
        // Heading 180: open sea (no skyline) in the middle columns.
        let level = r.render(Pose { heading: 175.0, ..Pose::default() });
        let down = r.render(Pose { heading: 175.0, pitch: -5.0, ..Pose::default() });
        let h0 = horizon(&level, 320, 240, 160);
        assert!((118..=122).contains(&h0), "level: the horizon in the middle ({h0})");
        assert!(horizon(&down, 320, 240, 160) < h0 - 20, "nose down: the horizon rises");
        let rolled = r.render(Pose { heading: 175.0, roll: 10.0, ..Pose::default() });
        let (left, right) = (horizon(&rolled, 320, 240, 120), horizon(&rolled, 320, 240, 200));
        assert!(left > right + 5, "rolled right: the horizon higher on the right ({left} {right})");
    }

    #[test]
    fn the_skyline_slides_with_heading_and_the_heading_scale_stands_on_the_horizon() {
        let r = Renderer::new(320, 240, Lens::Drive, VehicleKind::Usv);
        let a = r.render(Pose { heading: 60.0, ..Pose::default() });
        let b = r.render(Pose { heading: 70.0, ..Pose::default() });
        assert_ne!(a, b);
        // The headland (20..110°) fills the middle at 60°, the harbour front is not in view.
        assert!(horizon(&a, 320, 240, 160) < 117, "the headland stands above the horizon");
        let open = r.render(Pose { heading: 175.0, ..Pose::default() });
        assert!(horizon(&open, 320, 240, 160) >= 118, "open sea at 175°");
        // The heading scale: north's tick, in red, stands on the horizon in the middle at 0°.
        let north = r.render(Pose { heading: 0.0, ..Pose::default() });
        assert_eq!(at(&north, 320, 160, 117), [239, 68, 68]);
    }

    #[test]
    fn a_payload_camera_is_monochrome_narrow_and_pointed_by_its_head() {
        let r = Renderer::new(320, 240, Lens::Payload, VehicleKind::Usv);
        let px = r.render(Pose { heading: 60.0, ..Pose::default() });
        assert!(px.chunks_exact(3).all(|p| p[0] == p[1] && p[1] == p[2]), "grey everywhere");
        let panned = r.render(Pose { heading: 60.0, pan: 120.0, ..Pose::default() });
        assert_ne!(px, panned, "pan turns the view");
        let tilted = r.render(Pose { heading: 175.0, tilt: -3.0, ..Pose::default() });
        let level = r.render(Pose { heading: 175.0, ..Pose::default() });
        let row = |px: &[u8]| (40..240).find(|&y| at(px, 320, 40, y)[0] < 120).unwrap_or(240);
        assert!(row(&tilted) < row(&level), "tilted down: the horizon rises");
    }

    #[test]
    fn frames_have_no_counter_row() {
        let r = Renderer::new(64, 48, Lens::Drive, VehicleKind::Ugv);
        let a = r.render(Pose::default());
        assert_eq!(a.len(), 64 * 48 * 3);
        assert_eq!(a, r.render(Pose::default()), "the same pose, the same picture");
    }
}
