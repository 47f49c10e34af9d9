//! A window on a software GPU adapter (llvmpipe, lavapipe, SwiftShader, WARP): the layers
//! are composited by tiny-skia on the CPU, only the damage is uploaded, and the adapter
//! does no more than show the frame. Compositing every layer on such an adapter costs a
//! full-screen draw per layer per frame (about 7 fps under Xvfb for fig3).

use crate::compose::{CpuCompositor, LayerView};
use crate::display::Compositor;
use crate::geom::IRect;
use crate::gpu::GpuCompositor;
use tiny_skia::Pixmap;

/// Which compositor a window uses on an adapter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WindowPath {
    /// Layers composited on the GPU.
    Gpu,
    /// Layers composited on the CPU; the adapter only shows the frame.
    Cpu,
}

/// The path for an adapter: the CPU for a software rasteriser (its device type is `Cpu`,
/// or its name is one of the known ones), the GPU otherwise. `MOCU_COMPOSITOR=cpu|gpu`
/// (the `choice` argument) overrides.
pub fn choose_path(info: &wgpu::AdapterInfo, choice: Option<&str>) -> WindowPath {
    choose(&info.name, info.device_type, choice)
}

fn choose(name: &str, device_type: wgpu::DeviceType, choice: Option<&str>) -> WindowPath {
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

/// tiny-skia composites, the window's adapter presents.
pub(crate) struct CpuPresenter {
    cpu: CpuCompositor,
    gpu: GpuCompositor,
}

impl CpuPresenter {
    pub(crate) fn new(cpu: CpuCompositor, gpu: GpuCompositor) -> CpuPresenter {
        CpuPresenter { cpu, gpu }
    }
}

impl Compositor for CpuPresenter {
    fn name(&self) -> String {
        format!("tiny-skia, shown through {}", self.gpu.adapter_name())
    }

    fn resize(&mut self, width: u32, height: u32) {
        CpuCompositor::resize(&mut self.cpu, width, height);
        Compositor::resize(&mut self.gpu, width, height);
        let all = IRect::new(0, 0, width as i32, height as i32);
        self.gpu.upload_frame(self.cpu.frame(), all);
    }

    fn composite(&mut self, layers: &[LayerView<'_>], damage: IRect) {
        CpuCompositor::composite(&mut self.cpu, layers, damage);
        self.gpu.upload_frame(self.cpu.frame(), damage);
    }

    fn read_frame(&mut self) -> Pixmap {
        self.cpu.frame().clone()
    }

    fn present(&mut self) -> bool {
        self.gpu.present()
    }

    fn resize_surface(&mut self, width: u32, height: u32) {
        self.gpu.resize_surface(width, height);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn software_adapters_get_the_cpu_compositor_and_hardware_the_gpu() {
        use wgpu::DeviceType::*;
        let cases = [
            ("llvmpipe (LLVM 15.0.6, 256 bits)", Other, None, WindowPath::Cpu),
            ("llvmpipe (LLVM 15.0.6, 256 bits)", Cpu, None, WindowPath::Cpu),
            ("Lavapipe", Other, None, WindowPath::Cpu),
            ("SwiftShader Device", Other, None, WindowPath::Cpu),
            ("Some rasteriser", Cpu, None, WindowPath::Cpu),
            ("NVIDIA GeForce RTX 3060", DiscreteGpu, None, WindowPath::Gpu),
            ("Mesa Intel(R) UHD Graphics 620", IntegratedGpu, None, WindowPath::Gpu),
            ("llvmpipe", Cpu, Some("gpu"), WindowPath::Gpu),
            ("NVIDIA GeForce RTX 3060", DiscreteGpu, Some("CPU"), WindowPath::Cpu),
            ("NVIDIA GeForce RTX 3060", DiscreteGpu, Some("auto"), WindowPath::Gpu),
        ];
        for (name, ty, choice, want) in cases {
            assert_eq!(choose(name, ty, choice), want, "{name} {ty:?} {choice:?}");
        }
    }
}
