//! Choosing a graphics backend and adapter, headless, and opening a device on it.
//!
//! `Backend::Auto` honours the `MVGRASP_RENDER_BACKEND` environment variable (`auto`, `vulkan`,
//! `gl`, `metal`, `dx12`), then prefers a hardware GPU over a CPU rasteriser and, at equal
//! kind, Vulkan / Metal / DX12 over GL. An explicit backend ignores the variable.

use std::sync::{Arc, Mutex};

use crate::error::{INSTALL_HINT, RenderError, Result};

/// Environment variable that picks the backend when [`Backend::Auto`] is asked for.
pub const BACKEND_ENV: &str = "MVGRASP_RENDER_BACKEND";

/// Which graphics API to render with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Backend {
    /// `MVGRASP_RENDER_BACKEND` if set, else the best adapter available.
    #[default]
    Auto,
    /// Vulkan (on a machine without a GPU: Mesa's lavapipe).
    Vulkan,
    /// OpenGL ES through EGL (on a machine without a GPU: Mesa's llvmpipe).
    Gl,
    /// Metal (macOS).
    Metal,
    /// Direct3D 12 (Windows).
    Dx12,
}

impl Backend {
    /// Parses a backend name as `MVGRASP_RENDER_BACKEND` takes it (case-insensitive).
    pub fn parse(name: &str) -> Option<Self> {
        match name.trim().to_ascii_lowercase().as_str() {
            "" | "auto" => Some(Self::Auto),
            "vulkan" | "vk" => Some(Self::Vulkan),
            "gl" | "gles" | "opengl" => Some(Self::Gl),
            "metal" | "mtl" => Some(Self::Metal),
            "dx12" | "d3d12" => Some(Self::Dx12),
            _ => None,
        }
    }

    /// `Auto` replaced by the environment's choice, when it makes one.
    fn resolve(self) -> Result<Self> {
        if self != Self::Auto {
            return Ok(self);
        }
        match std::env::var(BACKEND_ENV) {
            Ok(value) => Self::parse(&value).ok_or(RenderError::InvalidParameter {
                op: "choose a render backend",
                name: BACKEND_ENV,
                value,
                expected: "auto, vulkan, gl, metal or dx12",
            }),
            Err(_) => Ok(Self::Auto),
        }
    }

    fn backends(self) -> wgpu::Backends {
        match self {
            Self::Auto => wgpu::Backends::PRIMARY | wgpu::Backends::GL,
            Self::Vulkan => wgpu::Backends::VULKAN,
            Self::Gl => wgpu::Backends::GL,
            Self::Metal => wgpu::Backends::METAL,
            Self::Dx12 => wgpu::Backends::DX12,
        }
    }
}

/// An open device with what the renderer keeps of its adapter.
pub(crate) struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub limits: wgpu::Limits,
    /// Errors the backend raised outside any scope, drained after each operation.
    pub errors: Arc<Mutex<Vec<String>>>,
}

/// Formats an adapter as "name (backend, driver)".
pub(crate) fn describe(info: &wgpu::AdapterInfo) -> String {
    let driver = [info.driver.as_str(), info.driver_info.as_str()]
        .iter()
        .filter(|s| !s.is_empty())
        .copied()
        .collect::<Vec<_>>()
        .join(" ");
    if driver.is_empty() {
        format!("{} ({:?})", info.name, info.backend)
    } else {
        format!("{} ({:?}, {driver})", info.name, info.backend)
    }
}

/// Rank of an adapter, higher is better: hardware before software, native APIs before GL.
fn rank(device_type: wgpu::DeviceType, backend: wgpu::Backend) -> (u8, u8) {
    let kind = match device_type {
        wgpu::DeviceType::DiscreteGpu => 4,
        wgpu::DeviceType::IntegratedGpu => 3,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 1,
        wgpu::DeviceType::Cpu => 0,
    };
    let api = u8::from(backend != wgpu::Backend::Gl);
    (kind, api)
}

/// Finds an adapter for `backend` and opens a device on it, with the adapter's own limits.
pub(crate) fn open(backend: Backend) -> Result<Gpu> {
    let backend = backend.resolve()?;
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = backend.backends();
    // Debug builds would otherwise ask for Vulkan validation layers and GL debug output; they
    // are slow and usually not installed. WGPU_DEBUG / WGPU_VALIDATION turn them back on.
    desc.flags = wgpu::InstanceFlags::empty().with_env();
    let instance = wgpu::Instance::new(desc);
    let adapters = pollster::block_on(instance.enumerate_adapters(backend.backends()));
    let mut rejected = Vec::new();
    let mut usable = Vec::new();
    for adapter in adapters {
        match supports_targets(&adapter) {
            Ok(()) => usable.push(adapter),
            Err(why) => rejected.push((describe(&adapter.get_info()), why)),
        }
    }
    let Some(adapter) = usable.into_iter().max_by_key(|a| {
        let info = a.get_info();
        rank(info.device_type, info.backend)
    }) else {
        if let Some((adapter, missing)) = rejected.first() {
            return Err(RenderError::UnsupportedAdapter {
                adapter: adapter.clone(),
                missing: missing.clone(),
            });
        }
        return Err(RenderError::NoAdapter {
            requested: format!("{backend:?}"),
            hint: INSTALL_HINT,
        });
    };
    let info = adapter.get_info();
    let limits = adapter.limits();
    let device_desc = wgpu::DeviceDescriptor {
        label: Some("mvgrasp-render"),
        required_features: wgpu::Features::empty(),
        required_limits: limits.clone(),
        ..Default::default()
    };
    let (device, queue) =
        pollster::block_on(adapter.request_device(&device_desc)).map_err(|e| {
            RenderError::RequestDevice {
                adapter: describe(&info),
                message: e.to_string(),
            }
        })?;
    let errors = Arc::new(Mutex::new(Vec::new()));
    let sink = Arc::clone(&errors);
    device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
        let mut v = sink.lock().unwrap_or_else(|p| p.into_inner());
        v.push(e.to_string());
    }));
    Ok(Gpu {
        device,
        queue,
        info,
        limits,
        errors,
    })
}

/// Checks that the adapter can render to and copy from the formats the renderer uses.
fn supports_targets(adapter: &wgpu::Adapter) -> std::result::Result<(), String> {
    use wgpu::TextureUsages as U;
    for (format, usages) in [
        (
            crate::targets::COLOR_FORMAT,
            U::RENDER_ATTACHMENT | U::COPY_SRC,
        ),
        (
            crate::targets::DEPTH_OUT_FORMAT,
            U::RENDER_ATTACHMENT | U::COPY_SRC,
        ),
        (crate::targets::ZBUFFER_FORMAT, U::RENDER_ATTACHMENT),
    ] {
        let features = adapter.get_texture_format_features(format);
        if !features.allowed_usages.contains(usages) {
            return Err(format!("{format:?} cannot be used as {usages:?}"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn backend_names_parse() {
        assert_eq!(Backend::parse("GL"), Some(Backend::Gl));
        assert_eq!(Backend::parse(" vulkan "), Some(Backend::Vulkan));
        assert_eq!(Backend::parse(""), Some(Backend::Auto));
        assert_eq!(Backend::parse("dx11"), None);
        assert_eq!(Backend::Vulkan.resolve().unwrap(), Backend::Vulkan);
    }

    #[test]
    fn hardware_outranks_software_and_native_outranks_gl() {
        use wgpu::{Backend as B, DeviceType as D};
        let cpu_gl = rank(D::Cpu, B::Gl);
        let cpu_vk = rank(D::Cpu, B::Vulkan);
        let gpu_gl = rank(D::DiscreteGpu, B::Gl);
        assert!(cpu_vk > cpu_gl && gpu_gl > cpu_vk);
    }
}
