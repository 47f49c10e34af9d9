//! A window without a hardware GPU adapter (none at all, or a software rasteriser such as
//! llvmpipe, lavapipe, SwiftShader or WARP): the layers are composited by tiny-skia on
//! the CPU and the frame is shown by softbuffer (X11 shared memory), with no GL or Vulkan
//! in between. Only the damage is converted and sent to the window. Through a software
//! adapter the same frame showed at about 8 fps under Xvfb (every present a full-screen
//! texture draw on the CPU); softbuffer shows it at the display rate.

use crate::compose::{CpuCompositor, LayerView};
use crate::display::{Compositor, DisplayError};
use crate::geom::IRect;
use std::num::NonZeroU32;
use std::sync::Arc;
use tiny_skia::Pixmap;
use winit::window::Window;

/// Which compositor a window uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WindowPath {
    /// Layers composited on the GPU (wgpu), presented by its surface.
    Gpu,
    /// Layers composited on the CPU (tiny-skia), the frame shown by softbuffer.
    Cpu,
}

impl WindowPath {
    /// Why this path, for the line `mocu run` prints.
    pub fn reason(self, adapter: Option<&wgpu::AdapterInfo>, choice: Option<&str>) -> String {
        let forced =
            matches!(choice.map(str::to_ascii_lowercase).as_deref(), Some("cpu") | Some("gpu"));
        match (self, adapter) {
            _ if forced => format!("MOCU_COMPOSITOR={}", choice.unwrap_or_default()),
            (WindowPath::Gpu, Some(a)) => format!("hardware adapter `{}`", a.name),
            (WindowPath::Cpu, Some(a)) => format!("software adapter `{}`", a.name),
            (_, None) => "no GPU adapter".into(),
        }
    }
}

/// The path for the adapter wgpu found for the window (`None`: none): the CPU for none or
/// a software rasteriser (its device type is `Cpu`, or its name is one of the known
/// ones), the GPU otherwise. `MOCU_COMPOSITOR=cpu|gpu` (the `choice` argument)
/// overrides; `gpu` without an adapter still gets the CPU.
pub fn choose_path(adapter: Option<&wgpu::AdapterInfo>, choice: Option<&str>) -> WindowPath {
    choose(adapter.map(|a| (a.name.as_str(), a.device_type)), choice)
}

fn choose(adapter: Option<(&str, wgpu::DeviceType)>, choice: Option<&str>) -> WindowPath {
    let Some((name, device_type)) = adapter else { return WindowPath::Cpu };
    match choice.map(str::to_ascii_lowercase).as_deref() {
        Some("cpu") => return WindowPath::Cpu,
        Some("gpu") => return WindowPath::Gpu,
        _ => {}
    }
    if is_software(name, device_type) { WindowPath::Cpu } else { WindowPath::Gpu }
}

/// Whether an adapter rasterises in software.
fn is_software(name: &str, device_type: wgpu::DeviceType) -> bool {
    let name = name.to_ascii_lowercase();
    device_type == wgpu::DeviceType::Cpu
        || ["llvmpipe", "lavapipe", "softpipe", "swiftshader", "microsoft basic render"]
            .iter()
            .any(|s| name.contains(s))
}

/// How many presented frames' damage is remembered: a window buffer older than that is
/// redrawn whole.
const HISTORY: usize = 4;

/// tiny-skia composites, softbuffer shows the frame in the window.
pub(crate) struct SoftPresenter {
    cpu: CpuCompositor,
    surface: softbuffer::Surface<Arc<Window>, Arc<Window>>,
    /// The window's inner size (the display's size does not follow it).
    window: (u32, u32),
    /// The damage composited since the last present.
    pending: IRect,
    /// The damage of the last presents, newest first.
    history: Vec<IRect>,
    /// Everything must be shown again (first frame, resized).
    full: bool,
}

fn soft_error(e: impl std::fmt::Display) -> DisplayError {
    DisplayError::Window(format!("softbuffer: {e}"))
}

impl SoftPresenter {
    pub(crate) fn new(cpu: CpuCompositor, window: Arc<Window>) -> Result<Self, DisplayError> {
        let context = softbuffer::Context::new(window.clone()).map_err(soft_error)?;
        let surface = softbuffer::Surface::new(&context, window.clone()).map_err(soft_error)?;
        let size = window.inner_size();
        Ok(SoftPresenter {
            cpu,
            surface,
            window: (size.width, size.height),
            pending: IRect::default(),
            history: Vec::new(),
            full: true,
        })
    }
}

impl Compositor for SoftPresenter {
    fn name(&self) -> String {
        "tiny-skia, shown by softbuffer".into()
    }

    fn resize(&mut self, width: u32, height: u32) {
        CpuCompositor::resize(&mut self.cpu, width, height);
        self.full = true;
    }

    fn composite(&mut self, layers: &[LayerView<'_>], damage: IRect) {
        CpuCompositor::composite(&mut self.cpu, layers, damage);
        self.pending = self.pending.union(&damage);
    }

    fn read_frame(&mut self) -> Pixmap {
        self.cpu.frame().clone()
    }

    fn present(&mut self) -> bool {
        let (ww, wh) = self.window;
        let (Some(nw), Some(nh)) = (NonZeroU32::new(ww), NonZeroU32::new(wh)) else {
            return false;
        };
        if self.surface.resize(nw, nh).is_err() {
            return false;
        }
        let Ok(mut buffer) = self.surface.buffer_mut() else { return false };
        let window = IRect::new(0, 0, ww as i32, wh as i32);
        let stale = stale_part(self.full, self.pending, &self.history, buffer.age());
        let part = stale.unwrap_or(window).intersect(&window);
        copy_frame(self.cpu.frame(), &mut buffer, ww as usize, part);
        let shown = if part.is_empty() {
            true
        } else {
            let rect = softbuffer::Rect {
                x: part.x as u32,
                y: part.y as u32,
                width: NonZeroU32::new(part.w as u32).unwrap_or(nw),
                height: NonZeroU32::new(part.h as u32).unwrap_or(nh),
            };
            buffer.present_with_damage(&[rect]).is_ok()
        };
        // What changed in this frame, for the older buffers: all of it when it was redrawn.
        let changed = std::mem::take(&mut self.pending);
        self.history.insert(0, if stale.is_none() { window } else { changed });
        self.history.truncate(HISTORY);
        self.full = !shown;
        shown
    }

    fn resize_surface(&mut self, width: u32, height: u32) {
        if (width, height) != self.window {
            self.window = (width, height);
            self.full = true;
        }
    }
}

/// What a window buffer needs redrawn, given its age (frames since it was last shown; 0:
/// new), the damage composited since the last present and that of the presents before.
/// `None`: all of it — also when nothing was composited since: a present without a new
/// frame is the window asking to be shown again (exposed), whatever its buffer holds.
fn stale_part(full: bool, pending: IRect, history: &[IRect], age: u8) -> Option<IRect> {
    let age = age as usize;
    if full || pending.is_empty() || age == 0 || age > history.len() + 1 {
        return None;
    }
    Some(history.iter().take(age - 1).fold(pending, |a, r| a.union(r)))
}

/// Writes `part` of the window buffer (`0RGB` words, `stride` a row) from the frame
/// (premultiplied RGBA8, shown over black); outside the frame the window is black.
fn copy_frame(frame: &Pixmap, buffer: &mut [u32], stride: usize, part: IRect) {
    let fw = frame.width() as usize;
    let inside = part.intersect(&IRect::new(0, 0, frame.width() as i32, frame.height() as i32));
    let (px, _) = frame.data().as_chunks::<4>();
    for y in part.y..part.bottom() {
        let row = &mut buffer[y as usize * stride..][part.x as usize..part.right() as usize];
        if inside.is_empty() || y < inside.y || y >= inside.bottom() {
            row.fill(0);
            continue;
        }
        // Each word written once: black beside the frame, the frame's pixels inside it.
        let (left, rest) = row.split_at_mut((inside.x - part.x) as usize);
        let (dst, right) = rest.split_at_mut(inside.w as usize);
        left.fill(0);
        right.fill(0);
        let src = &px[y as usize * fw + inside.x as usize..][..inside.w as usize];
        to_0rgb(dst, src);
    }
}

/// Premultiplied RGBA8 over black is its colour: `0RGB` words, the red and blue bytes
/// swapped within each little-endian word (lane arithmetic the compiler vectorises).
fn to_0rgb(dst: &mut [u32], src: &[[u8; 4]]) {
    for (d, p) in dst.iter_mut().zip(src) {
        let v = u32::from_le_bytes(*p);
        *d = ((v & 0xff) << 16) | (v & 0xff00) | ((v >> 16) & 0xff);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_adapter_or_a_software_one_gets_the_cpu_path_and_hardware_the_gpu() {
        use wgpu::DeviceType::*;
        let cases = [
            (Some(("llvmpipe (LLVM 15.0.6, 256 bits)", Other)), None, WindowPath::Cpu),
            (Some(("llvmpipe (LLVM 15.0.6, 256 bits)", Cpu)), None, WindowPath::Cpu),
            (Some(("Lavapipe", Other)), None, WindowPath::Cpu),
            (Some(("SwiftShader Device", Other)), None, WindowPath::Cpu),
            (Some(("Some rasteriser", Cpu)), None, WindowPath::Cpu),
            (None, None, WindowPath::Cpu),
            (None, Some("gpu"), WindowPath::Cpu),
            (Some(("NVIDIA GeForce RTX 3060", DiscreteGpu)), None, WindowPath::Gpu),
            (Some(("Mesa Intel(R) UHD Graphics 620", IntegratedGpu)), None, WindowPath::Gpu),
            (Some(("llvmpipe", Cpu)), Some("gpu"), WindowPath::Gpu),
            (Some(("NVIDIA GeForce RTX 3060", DiscreteGpu)), Some("CPU"), WindowPath::Cpu),
            (Some(("NVIDIA GeForce RTX 3060", DiscreteGpu)), Some("auto"), WindowPath::Gpu),
        ];
        for (adapter, choice, want) in cases {
            assert_eq!(choose(adapter, choice), want, "{adapter:?} {choice:?}");
        }
    }

    #[test]
    fn a_window_buffer_is_redrawn_where_it_missed_frames_and_whole_when_new_or_too_old() {
        let r = |x| IRect::new(x, 0, 1, 1);
        let history = [r(1), r(2), r(3)];
        assert_eq!(stale_part(false, r(0), &history, 1), Some(r(0)));
        assert_eq!(stale_part(false, r(0), &history, 3), Some(IRect::new(0, 0, 3, 1)));
        assert_eq!(stale_part(false, r(0), &history, 4), Some(IRect::new(0, 0, 4, 1)));
        assert_eq!(stale_part(false, r(0), &history, 5), None);
        assert_eq!(stale_part(false, r(0), &history, 0), None);
        assert_eq!(stale_part(true, r(0), &history, 1), None);
        assert_eq!(stale_part(false, IRect::default(), &history, 1), None, "exposed");
    }

    #[test]
    fn the_window_buffer_gets_the_frame_as_0rgb_over_black_and_black_outside_it() {
        let mut frame = Pixmap::new(3, 2).unwrap();
        frame.data_mut().copy_from_slice(&[
            255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, //
            16, 32, 48, 255, 8, 4, 2, 128, 0, 0, 0, 0,
        ]);
        let mut buffer = vec![0xdead_beef; 4 * 3];
        copy_frame(&frame, &mut buffer, 4, IRect::new(0, 0, 4, 3));
        assert_eq!(
            buffer,
            [
                0xff0000, 0x00ff00, 0x0000ff, 0, //
                0x102030, 0x080402, 0, 0, //
                0, 0, 0, 0,
            ]
        );
        // Only the part asked for is written.
        let mut buffer = vec![7; 4 * 3];
        copy_frame(&frame, &mut buffer, 4, IRect::new(1, 1, 1, 1));
        assert_eq!(buffer, [7, 7, 7, 7, 7, 0x080402, 7, 7, 7, 7, 7, 7]);
    }
}
