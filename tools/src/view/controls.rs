//! The viewer's input: mouse and keys turned into camera moves, object
//! drags and edits, effect switches and preset changes, applied to the
//! [`InsertionView`] between frames. Key bindings are listed in
//! [`help`].

use glam::DVec3;
use inlay_passes::march::MarchKnobs;
use inlay_passes::object::{PlacedObject, Scale};
use inlay_passes::scene::Scene;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::keyboard::{KeyCode, PhysicalKey};

use super::orbit::OrbitCamera;
use super::picking::{field_surface, pick_visible, rest_on};
use crate::insertion_view::InsertionView;
use crate::window_app::Response;
use inlay_passes::frame::effect_switches;

/// The key bindings, as the overlay's help shows them: the effect
/// switches as the frame's passes declare them ([`effect_switches`]).
pub fn help() -> Vec<String> {
    let effects: Vec<String> = effect_switches()
        .iter()
        .map(|s| format!("{} {}", s.key, s.name))
        .collect();
    vec![
        "drag object: move on field  L-drag: orbit/look".into(),
        "R-drag: pan  wheel: zoom  Tab: orbit/fly  WASD".into(),
        "Q/E rotate  +/- or Shift+wheel: scale".into(),
        "[ ] roughness  ; ' metallic  C colour  X reset".into(),
        effects.join("  "),
        "F5 quality preset  O overlay  H help  Esc quit".into(),
    ]
}

/// The function key a label such as `F3` names.
fn function_key(label: &str) -> Option<KeyCode> {
    const KEYS: [KeyCode; 12] = [
        KeyCode::F1,
        KeyCode::F2,
        KeyCode::F3,
        KeyCode::F4,
        KeyCode::F5,
        KeyCode::F6,
        KeyCode::F7,
        KeyCode::F8,
        KeyCode::F9,
        KeyCode::F10,
        KeyCode::F11,
        KeyCode::F12,
    ];
    let n: usize = label.strip_prefix('F')?.parse().ok()?;
    KEYS.get(n.checked_sub(1)?).copied()
}

/// Base colours `C` cycles through (linear RGB).
const PALETTE: [[f64; 3]; 5] = [
    [0.8, 0.8, 0.8],
    [0.8, 0.08, 0.06],
    [0.1, 0.55, 0.12],
    [0.08, 0.2, 0.8],
    [0.95, 0.7, 0.15],
];

/// What a mouse drag is doing.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Drag {
    None,
    /// Turning the camera (about the target, or the eye when flying).
    Turn,
    /// Moving the camera sideways.
    Pan,
    /// Dragging object `index` across the field.
    Object(usize),
}

/// Input state of the viewer.
pub struct Controls {
    /// The camera.
    pub camera: OrbitCamera,
    /// Fly mode: mouse looks about the eye (else orbits the target).
    pub fly: bool,
    /// The object edits apply to.
    pub selected: Option<usize>,
    /// Whether the help lines are shown.
    pub help: bool,
    /// What the overlay shows.
    pub overlay: super::hud::Overlay,
    /// Edits made so far (moves, rotations, material changes).
    pub edits: u64,
    /// Edits included in the frame being built (set by the overlay call
    /// that precedes each frame's build).
    pub built_edits: u64,
    /// Edits already reported as shown.
    pub announced_edits: u64,
    /// The drawable size seen last.
    pub extent: (u32, u32),
    drag: Drag,
    cursor: (f64, f64),
    shift: bool,
    palette_next: usize,
    march: MarchKnobs,
    /// The scene file's placements (`X` resets to them).
    authored: Vec<PlacedObject>,
}

impl Controls {
    /// Controls starting at `camera`, with the first object selected.
    pub fn new(camera: OrbitCamera, scene: &Scene, overlay: super::hud::Overlay) -> Self {
        Self {
            camera,
            fly: false,
            selected: (!scene.objects.is_empty()).then_some(0),
            help: false,
            overlay,
            edits: 0,
            built_edits: 0,
            announced_edits: 0,
            extent: (1, 1),
            drag: Drag::None,
            cursor: (0.0, 0.0),
            shift: false,
            palette_next: 0,
            march: scene.march,
            authored: scene.objects.clone(),
        }
    }

    /// Whether a mouse drag is under way.
    pub fn dragging(&self) -> bool {
        self.drag != Drag::None
    }

    /// Applies `event` to `view`; `field` is the CPU field for picking.
    pub fn handle(
        &mut self,
        event: &WindowEvent,
        extent: (u32, u32),
        view: &mut InsertionView,
        field: &inlay_passes::field::GridField,
    ) -> Response {
        self.extent = extent;
        match event {
            WindowEvent::ModifiersChanged(m) => self.shift = m.state().shift_key(),
            WindowEvent::CursorMoved { position, .. } => {
                let (x, y) = (position.x, position.y);
                let (dx, dy) = (x - self.cursor.0, y - self.cursor.1);
                self.cursor = (x, y);
                self.mouse_moved(dx, dy, extent, view, field);
            }
            WindowEvent::MouseInput { state, button, .. } => {
                self.mouse_button(*state, *button, extent, view, field)
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => *y as f64,
                    MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
                };
                if self.shift && self.selected.is_some() {
                    self.scale_selected(view, 1.1f64.powf(steps));
                } else {
                    self.camera.zoom(0.9f64.powf(steps));
                    self.update_camera(view);
                }
            }
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    return self.key(code, view);
                }
            }
            _ => {}
        }
        Response::Continue
    }

    fn update_camera(&self, view: &mut InsertionView) {
        view.set_camera(self.camera.spec());
    }

    fn mouse_button(
        &mut self,
        state: ElementState,
        button: MouseButton,
        extent: (u32, u32),
        view: &mut InsertionView,
        field: &inlay_passes::field::GridField,
    ) {
        if state == ElementState::Released {
            if let Drag::Object(i) = self.drag {
                self.report_move(i, view, extent);
            }
            self.drag = Drag::None;
            return;
        }
        self.drag = match button {
            MouseButton::Left => {
                let frame = view.frame(extent.0.max(1), extent.1.max(1));
                let ray = frame.ray(self.cursor.0, self.cursor.1);
                let placed: Vec<PlacedObject> = (0..view.objects().len())
                    .filter_map(|i| view.placed(i))
                    .collect();
                match pick_visible(&placed, &ray, field, &self.march, view.effects().occlusion) {
                    Some((i, _)) => {
                        self.selected = Some(i);
                        Drag::Object(i)
                    }
                    None => Drag::Turn,
                }
            }
            MouseButton::Right | MouseButton::Middle => Drag::Pan,
            _ => Drag::None,
        };
    }

    fn mouse_moved(
        &mut self,
        dx: f64,
        dy: f64,
        extent: (u32, u32),
        view: &mut InsertionView,
        field: &inlay_passes::field::GridField,
    ) {
        let per_pixel = self.camera.fov_y.to_radians() / extent.1.max(1) as f64;
        match self.drag {
            Drag::None => {}
            Drag::Turn => {
                if self.fly {
                    self.camera.look(dx * per_pixel, -dy * per_pixel);
                } else {
                    self.camera
                        .orbit(dx * per_pixel * 2.0, -dy * per_pixel * 2.0);
                }
                self.update_camera(view);
            }
            Drag::Pan => {
                let d = self.camera.distance * per_pixel;
                self.camera.translate(-dx * d, dy * d, 0.0);
                self.update_camera(view);
            }
            Drag::Object(i) => {
                let frame = view.frame(extent.0.max(1), extent.1.max(1));
                let ray = frame.ray(self.cursor.0, self.cursor.1);
                // Off the field's surfaces the object stays where it was.
                if let (Some(surface), Some(mut p)) =
                    (field_surface(field, &ray, &self.march), view.placed(i))
                {
                    p.pose.position = rest_on(&p, surface);
                    view.set_placed(i, p);
                    self.edits += 1;
                }
            }
        }
    }

    fn report_move(&self, i: usize, view: &InsertionView, extent: (u32, u32)) {
        if let Some(p) = view.placed(i) {
            let at = p.pose.position;
            let pixel = view
                .frame(extent.0.max(1), extent.1.max(1))
                .project(p.sphere().0);
            println!(
                "view: moved `{}` to ({:.4}, {:.4}, {:.4}), now at pixel {}",
                p.name,
                at.x,
                at.y,
                at.z,
                pixel.map_or("(off screen)".into(), |(x, y)| format!("({x:.1}, {y:.1})"))
            );
        }
    }

    fn edit_selected(&mut self, view: &mut InsertionView, f: impl FnOnce(&mut PlacedObject)) {
        if let Some(mut p) = self.selected.and_then(|i| view.placed(i)) {
            let before = p.clone();
            f(&mut p);
            // Keep only edits the scene file would accept.
            if p.pose.problem().is_some() || p.material.problem().is_some() {
                p = before;
            }
            view.set_placed(self.selected.unwrap_or(0), p);
            self.edits += 1;
        }
    }

    fn scale_selected(&mut self, view: &mut InsertionView, factor: f64) {
        self.edit_selected(view, |p| {
            p.pose.scale = match p.pose.scale {
                Scale::Uniform(s) => Scale::Uniform(s * factor),
                Scale::PerAxis(v) => Scale::PerAxis(v * factor),
            }
        });
    }

    fn key(&mut self, code: KeyCode, view: &mut InsertionView) -> Response {
        let step = 0.05 * self.camera.distance;
        let mut effects = view.effects();
        match code {
            KeyCode::Escape => return Response::Quit,
            KeyCode::F5 => return Response::Rebuild,
            KeyCode::KeyH => {
                self.help = !self.help;
                self.overlay = super::hud::Overlay::Full;
            }
            KeyCode::KeyO => self.overlay = self.overlay.next(),
            KeyCode::Tab => self.fly = !self.fly,
            KeyCode::KeyW => self.camera.translate(0.0, 0.0, step),
            KeyCode::KeyS => self.camera.translate(0.0, 0.0, -step),
            KeyCode::KeyA => self.camera.translate(-step, 0.0, 0.0),
            KeyCode::KeyD => self.camera.translate(step, 0.0, 0.0),
            KeyCode::Space => self.camera.translate(0.0, step, 0.0),
            KeyCode::KeyZ => self.camera.translate(0.0, -step, 0.0),
            KeyCode::KeyQ => self.edit_selected(view, |p| p.pose.rotation.y += 15.0),
            KeyCode::KeyE => self.edit_selected(view, |p| p.pose.rotation.y -= 15.0),
            KeyCode::Equal | KeyCode::NumpadAdd => self.scale_selected(view, 1.1),
            KeyCode::Minus | KeyCode::NumpadSubtract => self.scale_selected(view, 1.0 / 1.1),
            KeyCode::BracketLeft => self.nudge(view, -0.05, 0.0),
            KeyCode::BracketRight => self.nudge(view, 0.05, 0.0),
            KeyCode::Semicolon => self.nudge(view, 0.0, -0.1),
            KeyCode::Quote => self.nudge(view, 0.0, 0.1),
            KeyCode::KeyC => {
                let c = PALETTE[self.palette_next % PALETTE.len()];
                self.palette_next += 1;
                self.edit_selected(view, |p| p.material.base_color = Some(DVec3::from(c)));
            }
            KeyCode::KeyX => {
                let authored = self.selected.and_then(|i| self.authored.get(i).cloned());
                if let Some(a) = authored {
                    self.edit_selected(view, |p| p.material = a.material);
                }
            }
            code if effect_switches()
                .iter()
                .any(|s| function_key(s.key) == Some(code)) =>
            {
                for s in effect_switches() {
                    if function_key(s.key) == Some(code) {
                        effects.set(s.effect, !effects.on(s.effect));
                    }
                }
            }
            _ => {}
        }
        view.set_effects(effects);
        self.update_camera(view);
        Response::Continue
    }

    /// Moves the selected object's roughness and metallic by the deltas,
    /// starting from its first material's values, clamped to [0, 1].
    fn nudge(&mut self, view: &mut InsertionView, roughness: f64, metallic: f64) {
        self.edit_selected(view, |p| {
            let m = p.material_of(0);
            p.material.roughness = Some((m.roughness + roughness).clamp(0.0, 1.0));
            p.material.metallic = Some((m.metallic + metallic).clamp(0.0, 1.0));
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every effect switch the passes declare has a key the viewer binds,
    /// and the help lists it.
    #[test]
    fn every_effect_switch_has_a_bound_key_and_a_help_entry() {
        let help = help().join("\n");
        for s in effect_switches() {
            let key = function_key(s.key);
            assert!(
                key.is_some(),
                "{}: key {} is not a function key",
                s.name,
                s.key
            );
            assert_ne!(key, Some(KeyCode::F5), "F5 switches the preset");
            assert!(help.contains(&format!("{} {}", s.key, s.name)), "{help}");
        }
        assert_eq!(function_key("F12"), Some(KeyCode::F12));
        assert_eq!(function_key("F0"), None);
        assert_eq!(function_key("G1"), None);
    }
}
