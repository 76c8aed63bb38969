//! The interactive viewer (cargo feature `viewer`; `skinkit view SCENE`): a winit window showing
//! the scene's first camera, orbited with the mouse, with the key light moved, the base pass's
//! ingredients and each of the scene's effects toggled from the keyboard.
//!
//! Frames are drawn by [`crate::view::ViewSession`]: the scene's pass graph (every effect it
//! lists, less those switched off) through the same offscreen passes as headless renders (an
//! Rgba8UnormSrgb target read back and shown through `softbuffer`), so what the window shows is
//! what `skinkit render` writes,
//! and it runs wherever the headless renderer does, lavapipe under a plain X server included. On
//! a hardware GPU a swapchain would save the readback; at viewer sizes it costs a few
//! milliseconds.
//!
//! Controls: left drag orbits the camera about its target, the wheel moves it closer or farther,
//! right drag moves the first light (azimuth and elevation about the camera's up axis); `N`
//! toggles the fine-scale normal map, `S` the specular lobes, `V` per-pixel / per-vertex specular,
//! `1` to `6` the scene's effects in the order it lists them, `R` resets the view, `Esc` or `Q`
//! quits. The title shows the state and the last frame's time.

use std::num::NonZeroU32;
use std::rc::Rc;
use std::time::Instant;

use glam::{Mat3, Vec3};
use winit::application::ApplicationHandler;
use winit::dpi::{LogicalSize, PhysicalPosition};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use crate::renderer::{RenderError, Renderer};
use crate::scene;
use crate::shading::LightKind;
use crate::view::{Toggles, ViewSession};

/// What went wrong opening or running the window.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ViewerError {
    /// No display, or the window system refused a window.
    #[error("cannot open a window ({0}): the viewer needs a display (X11 or Wayland; DISPLAY or WAYLAND_DISPLAY)")]
    Window(String),
    /// A frame could not be drawn.
    #[error(transparent)]
    Frame(#[from] RenderError),
}

/// The orbit camera: the scene camera's target and up, a direction and a distance.
#[derive(Clone, Copy, Debug)]
struct Orbit {
    start: scene::Camera,
    yaw: f32,
    pitch: f32,
    zoom: f32,
}

impl Orbit {
    fn camera(&self) -> scene::Camera {
        let c = self.start;
        let offset = c.position - c.target;
        let right = offset.cross(c.up).normalize_or_zero();
        let turn = Mat3::from_axis_angle(c.up, self.yaw);
        let tilt = if right == Vec3::ZERO { Mat3::IDENTITY } else { Mat3::from_axis_angle(right, self.pitch) };
        scene::Camera { position: c.target + turn * (tilt * offset) * self.zoom, ..c }
    }
}

struct App {
    renderer: Renderer,
    session: ViewSession,
    orbit: Orbit,
    toggles: Toggles,
    light_turn: (f32, f32),
    size: (u32, u32),
    /// The size the session last drew at (its targets follow the window).
    drawn: Option<(u32, u32)>,
    window: Option<Rc<Window>>,
    surface: Option<softbuffer::Surface<Rc<Window>, Rc<Window>>>,
    drag: Option<(MouseButton, PhysicalPosition<f64>)>,
    cursor: PhysicalPosition<f64>,
    error: Option<ViewerError>,
    last_frame_ms: f64,
}

/// Opens a window on `scene` (its first camera) and runs until it is closed.
///
/// # Errors
/// No display, or a renderer error.
pub fn run(renderer: Renderer, session: ViewSession) -> Result<(), ViewerError> {
    let scene = session.scene();
    let camera = scene.cameras[0];
    let toggles = Toggles::all_on(scene);
    let size = session.size();
    let event_loop = EventLoop::new().map_err(|e| ViewerError::Window(e.to_string()))?;
    let mut app = App {
        renderer,
        session,
        orbit: Orbit { start: camera, yaw: 0.0, pitch: 0.0, zoom: 1.0 },
        toggles,
        light_turn: (0.0, 0.0),
        size,
        drawn: None,
        window: None,
        surface: None,
        drag: None,
        cursor: PhysicalPosition::new(0.0, 0.0),
        error: None,
        last_frame_ms: 0.0,
    };
    event_loop.run_app(&mut app).map_err(|e| ViewerError::Window(e.to_string()))?;
    app.error.map_or(Ok(()), Err)
}

impl App {
    /// The first light turned by the right-drag angles about the camera's up axis and right axis.
    fn light(&self) -> Option<crate::shading::Light> {
        let light = self.session.first_light()?;
        let c = self.orbit.start;
        let right = (c.position - c.target).cross(c.up).normalize_or_zero();
        let turn = Mat3::from_axis_angle(c.up, self.light_turn.0)
            * if right == Vec3::ZERO { Mat3::IDENTITY } else { Mat3::from_axis_angle(right, self.light_turn.1) };
        let kind = match light.kind {
            LightKind::Directional { toward } => LightKind::Directional { toward: turn * toward },
            LightKind::Point { position } => LightKind::Point { position: c.target + turn * (position - c.target) },
        };
        Some(crate::shading::Light { kind, ..light })
    }

    fn draw(&mut self) -> Result<(), ViewerError> {
        let (w, h) = self.size;
        let fresh = self.drawn != Some((w, h));
        if fresh {
            self.session.resize(&self.renderer, w, h)?;
            self.drawn = Some((w, h));
        }
        let toggles = self.toggles.clone();
        let camera = self.orbit.camera();
        let light = self.light();
        let start = Instant::now();
        let frame = self.session.frame(&self.renderer, &toggles, &camera, light)?;
        self.last_frame_ms = start.elapsed().as_secs_f64() * 1e3;
        let (Some(surface), Some(window)) = (self.surface.as_mut(), self.window.as_ref()) else { return Ok(()) };
        let (Some(nw), Some(nh)) = (NonZeroU32::new(w), NonZeroU32::new(h)) else { return Ok(()) };
        // The surface follows the target: both change only when the window is resized.
        if fresh {
            surface.resize(nw, nh).map_err(|e| ViewerError::Window(e.to_string()))?;
        }
        let mut buffer = surface.buffer_mut().map_err(|e| ViewerError::Window(e.to_string()))?;
        for (dst, px) in buffer.iter_mut().zip(frame.srgb_bytes.chunks_exact(4)) {
            *dst = (u32::from(px[0]) << 16) | (u32::from(px[1]) << 8) | u32::from(px[2]);
        }
        buffer.present().map_err(|e| ViewerError::Window(e.to_string()))?;
        let effects: String = self
            .session
            .effects()
            .iter()
            .enumerate()
            .map(|(i, e)| format!(", {e} {} ({})", on(!toggles.off.contains(e)), i + 1))
            .collect();
        window.set_title(&format!(
            "skinkit view: normal map {} (N), specular {} (S), {} (V){effects}; {:.1} ms on {}",
            on(toggles.normal_map),
            on(toggles.specular),
            if toggles.vertex_specular { "per vertex" } else { "per pixel" },
            self.last_frame_ms,
            self.renderer.adapter_name()
        ));
        Ok(())
    }

    /// The scene effect a number key toggles (`1` is the first the scene lists).
    fn effect_key(&self, key: &str) -> Option<crate::effect::Effect> {
        let index: usize = key.parse().ok()?;
        self.session.effects().get(index.checked_sub(1)?).copied()
    }

    fn redraw(&self) {
        if let Some(w) = &self.window {
            w.request_redraw();
        }
    }
}

fn on(b: bool) -> &'static str {
    if b { "on" } else { "off" }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        let attributes = Window::default_attributes()
            .with_title("skinkit view")
            .with_inner_size(LogicalSize::new(self.size.0, self.size.1));
        let opened =
            event_loop.create_window(attributes).map_err(|e| ViewerError::Window(e.to_string())).and_then(|w| {
                let window = Rc::new(w);
                let context =
                    softbuffer::Context::new(window.clone()).map_err(|e| ViewerError::Window(e.to_string()))?;
                let surface = softbuffer::Surface::new(&context, window.clone())
                    .map_err(|e| ViewerError::Window(e.to_string()))?;
                Ok((window, surface))
            });
        match opened {
            Ok((window, surface)) => {
                let size = window.inner_size();
                self.size = (size.width.max(1), size.height.max(1));
                self.window = Some(window);
                self.surface = Some(surface);
                self.redraw();
            }
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                let size = (size.width.max(1), size.height.max(1));
                self.size = size;
                self.redraw();
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.draw() {
                    self.error = Some(e);
                    event_loop.exit();
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                self.drag = (state == ElementState::Pressed).then_some((button, self.cursor));
            }
            WindowEvent::CursorMoved { position, .. } => {
                self.cursor = position;
                if let Some((button, from)) = self.drag {
                    let (dx, dy) = ((position.x - from.x) as f32, (position.y - from.y) as f32);
                    let scale = std::f32::consts::PI / self.size.1.max(1) as f32;
                    match button {
                        MouseButton::Left => {
                            self.orbit.yaw -= dx * scale;
                            self.orbit.pitch = (self.orbit.pitch - dy * scale).clamp(-1.5, 1.5);
                        }
                        MouseButton::Right => {
                            self.light_turn.0 += dx * scale;
                            self.light_turn.1 = (self.light_turn.1 + dy * scale).clamp(-1.5, 1.5);
                        }
                        _ => {}
                    }
                    self.drag = Some((button, position));
                    self.redraw();
                }
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.orbit.zoom = (self.orbit.zoom * 0.9f32.powf(lines)).clamp(0.05, 20.0);
                self.redraw();
            }
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                match event.logical_key.as_ref() {
                    Key::Named(NamedKey::Escape) | Key::Character("q") => event_loop.exit(),
                    Key::Character("n") => self.toggles.normal_map = !self.toggles.normal_map,
                    Key::Character("s") => self.toggles.specular = !self.toggles.specular,
                    Key::Character("v") => self.toggles.vertex_specular = !self.toggles.vertex_specular,
                    Key::Character(digit) if self.effect_key(digit).is_some() => {
                        let effect = self.effect_key(digit).expect("checked by the guard");
                        self.toggles.flip(effect);
                    }
                    Key::Character("r") => {
                        self.orbit = Orbit { yaw: 0.0, pitch: 0.0, zoom: 1.0, ..self.orbit };
                        self.light_turn = (0.0, 0.0);
                    }
                    _ => return,
                }
                self.redraw();
            }
            _ => {}
        }
    }
}
