//! Everything the viewer knows between frames, and every action on it (keys, panel, script).
//! GL-free: the window loop renders what this state asks for and shows what it holds.

use super::error_job::{ErrorJob, ErrorResult};
use super::fly::{self, FlyInput};
use super::script::{Command, Toggle, ViewMode};
use crate::frame::Step;
use crate::gl::{FrameRequest, Overlays};
use crate::options::{Options, Technique};
use crate::scene::path::{self, PathKey};
use crate::scene::{Camera, Scene};
use std::collections::VecDeque;
use std::hash::{Hash, Hasher};
use std::path::PathBuf;
use std::sync::Arc;

/// Frame times kept for the graph.
pub const HISTORY: usize = 240;

/// The technique keys' cycle: none, the three maps, volumes, the hybrid, the subdivision, auto.
fn next_technique(t: Technique) -> Technique {
    match t {
        Technique::None => Technique::ShadowMap,
        Technique::ShadowMap => Technique::Psm,
        Technique::Psm => Technique::Tsm,
        Technique::Tsm => Technique::ShadowVolume,
        Technique::ShadowVolume => Technique::Hybrid,
        Technique::Hybrid => Technique::Subdivision,
        Technique::Subdivision => Technique::Auto,
        Technique::Auto => Technique::None,
    }
}

/// Scene edits from the panel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Action {
    /// Move the selected light to the camera.
    LightToCamera,
    /// Point the selected spot light at what the view's centre shows.
    AimLightAtView,
    AddSpot,
    AddOmni,
    RemoveLight,
    /// Stand the selected model where the view's centre looks.
    PlaceModel,
    /// A copy of the selected model there.
    CopyModel,
}

/// Files to write once the current frame is on screen.
#[derive(Debug, Clone, PartialEq)]
pub enum Pending {
    /// The whole window.
    Screenshot(PathBuf),
    /// The 3D view only.
    Frame(PathBuf),
}

/// Frames a script's `sampled N` may render before it gives up: the live error samples a
/// frame whenever its spending is under `estimate.budget` of the frames' time, so at a budget
/// of 0.1 about one frame in ten where masks cost a frame (llvmpipe).
const SAMPLED_FRAME_LIMIT: usize = 500;

pub struct ViewerState {
    pub scene: Arc<Scene>,
    pub options: Options,
    pub camera: Camera,
    pub selected_light: usize,
    pub selected_model: usize,
    /// Which of an omni light's six depth images the depth view shows.
    pub face: usize,
    pub view: ViewMode,
    pub overlays: Overlays,
    pub show_timings: bool,
    pub show_help: bool,
    /// The step the walkthrough stops after.
    pub walkthrough: Option<usize>,
    /// The steps of the last complete frame (how far the walkthrough can go).
    pub steps: Vec<Step>,
    pub fly: FlyInput,
    pub recording: Option<(PathBuf, Vec<PathKey>)>,
    pub replay: VecDeque<PathKey>,
    /// The last path recorded or replayed (F10 plays it again).
    pub last_path: Option<PathBuf>,
    pub frame_ms: VecDeque<f64>,
    pub vsync: bool,
    pub script: VecDeque<Command>,
    wait: usize,
    pub error_job: Option<ErrorJob>,
    /// Each frame sampled against the exact reference as it runs (E).
    pub live_error: super::live_error::LiveError,
    pub error_result: Option<(u64, ErrorResult)>,
    /// A script's `error` waits for the job.
    error_blocks: bool,
    /// A script's `sampled N` waits until the live error's sampled frames reach this count;
    /// the frames it may render meanwhile.
    wait_sampled: Option<(u64, usize)>,
    /// The last action's outcome, shown in the panel.
    pub status: String,
    pub quit: bool,
    /// The scene's surfaces changed: upload it again before rendering.
    pub needs_upload: bool,
    pub pending: Vec<Pending>,
    screenshots: usize,
    /// The scene's motion (players, moving lights): where in time, and whether it plays.
    pub clock: MotionClock,
    /// The selected light follows the camera at this offset (G: grab it, G again: drop it).
    pub grabbed: Option<glam::Vec3>,
}

/// The viewer's time in the scene's motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionClock {
    /// Seconds of scene time.
    pub time: f64,
    pub playing: bool,
}

impl MotionClock {
    /// One step of the scene's time: a path frame (1/20 s).
    pub const STEP: f64 = 1.0 / crate::scene::path::FRAME_RATE_HZ;

    /// Advances `dt` seconds while playing; steps `frames` path frames either way (not
    /// before 0).
    pub fn advance(&mut self, dt: f64, frames: i64) {
        if self.playing {
            self.time += dt;
        }
        self.time = (self.time + frames as f64 * Self::STEP).max(0.0);
    }
}

impl ViewerState {
    pub fn new(scene: Scene, options: Options, script: Vec<Command>) -> ViewerState {
        ViewerState {
            camera: scene.camera,
            scene: Arc::new(scene),
            options,
            selected_light: 0,
            selected_model: 0,
            face: 0,
            view: ViewMode::Scene,
            overlays: Overlays::default(),
            show_timings: true,
            show_help: false,
            walkthrough: None,
            steps: Vec::new(),
            fly: FlyInput::default(),
            recording: None,
            replay: VecDeque::new(),
            last_path: None,
            frame_ms: VecDeque::with_capacity(HISTORY),
            vsync: true,
            script: script.into(),
            // The first frame is complete before a script acts (the walkthrough needs its steps).
            wait: 1,
            error_job: None,
            live_error: Default::default(),
            error_result: None,
            error_blocks: false,
            wait_sampled: None,
            status: String::new(),
            quit: false,
            needs_upload: false,
            pending: Vec::new(),
            screenshots: 0,
            clock: MotionClock {
                time: 0.0,
                playing: true,
            },
            grabbed: None,
        }
    }

    /// What the current frame depends on: camera, options, lights and models.
    pub fn frame_key(&self) -> u64 {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        let c = &self.camera;
        [
            c.position.x,
            c.position.y,
            c.position.z,
            c.yaw_deg,
            c.pitch_deg,
            c.fov_x_deg,
        ]
        .map(f32::to_bits)
        .hash(&mut h);
        self.options.to_map().hash(&mut h);
        for l in &self.scene.lights {
            format!("{l:?}").hash(&mut h);
        }
        for m in &self.scene.models {
            m.transform.to_cols_array().map(f32::to_bits).hash(&mut h);
            m.pose.hash(&mut h);
        }
        self.scene.surfaces.len().hash(&mut h);
        h.finish()
    }

    /// The error image, if it was computed for the frame now on screen.
    pub fn current_error(&self) -> Option<&ErrorResult> {
        self.error_result
            .as_ref()
            .filter(|(k, _)| *k == self.frame_key())
            .map(|(_, r)| r)
    }

    /// What to ask the renderer for this frame.
    pub fn request(&self) -> FrameRequest {
        let wants_error = self.view == ViewMode::Error
            && self.current_error().is_none()
            && self.error_job.is_none();
        FrameRequest {
            masks: wants_error && self.walkthrough.is_none(),
            masks_drawn_again: false,
            // The error view's job reads the G-buffer whole; the live estimate only where it
            // picks.
            gbuffer_kept: !wants_error,
            stop_after: self.walkthrough,
            stencil_of: (self.view == ViewMode::Stencil).then_some(self.selected_light),
            // The selected light's volumes: all lights' at once hide each other.
            overlays: Overlays {
                light: Some(self.selected_light),
                ..self.overlays
            },
            // The timings overlay shows each pass.
            frame_only: false,
            // The window shows the frame's texture as it lies on the GPU; the pixels are read
            // back only for a walkthrough step's image or a script's frame capture.
            image_on_gpu: self.walkthrough.is_none()
                && !self.pending.iter().any(|p| matches!(p, Pending::Frame(_))),
            // Timer queries are read frames later, never waited for.
            pass_times_later: true,
        }
    }

    /// Moves the camera for one frame: a replayed pose, or the fly controls; a grabbed light
    /// goes with it.
    pub fn advance_camera(&mut self, dt: f32) {
        if let Some(k) = self.replay.pop_front() {
            self.camera = k.apply(&self.camera);
        } else if self.fly.moves() {
            fly::fly(&mut self.camera, &self.fly, dt);
        }
        self.fly.look = [0.0, 0.0];
        if let Some((_, keys)) = &mut self.recording {
            keys.push(PathKey::of(&self.camera));
        }
        if let Some(offset) = self.grabbed {
            let l = self.selected_light;
            let to = self.camera.position + offset;
            if self.scene.lights.get(l).is_some_and(|x| x.position != to) {
                Arc::make_mut(&mut self.scene).lights[l].position = to;
            }
        }
    }

    /// Advances the scene's motion by `dt` seconds (while playing) and `frames` steps, and
    /// poses the scene there. A grabbed light stays where the camera put it.
    pub fn advance_motion(&mut self, dt: f64, frames: i64) {
        if self.scene.motion.is_still() {
            return;
        }
        let before = self.clock.time;
        self.clock.advance(dt, frames);
        if self.clock.time != before || frames != 0 {
            let grabbed = self
                .grabbed
                .and(self.scene.lights.get(self.selected_light).cloned());
            let scene = Arc::make_mut(&mut self.scene);
            scene.pose_at(self.clock.time);
            if let Some(light) = grabbed {
                scene.lights[self.selected_light] = light;
            }
        }
    }

    /// Grabs the selected light (it keeps its offset from the camera as the camera moves),
    /// or drops it.
    pub fn toggle_grab(&mut self) {
        let l = self.selected_light;
        self.grabbed = match (self.grabbed, self.scene.lights.get(l)) {
            (None, Some(light)) => {
                self.status = format!("light {l} grabbed: it moves with the camera (G drops it)");
                Some(light.position - self.camera.position)
            }
            _ => {
                self.status = format!("light {l} dropped");
                None
            }
        };
    }

    /// Notes a finished frame's time and steps.
    pub fn frame_done(&mut self, frame_ms: f64, steps: &[Step]) {
        if self.frame_ms.len() == HISTORY {
            self.frame_ms.pop_front();
        }
        self.frame_ms.push_back(frame_ms);
        if self.walkthrough.is_none() {
            self.steps = steps.to_vec();
        }
    }

    /// Light `i`'s next technique: none → shadow map → shadow volume → none. An override equal
    /// to the global technique is dropped.
    pub fn cycle_light_technique(&mut self, i: usize) {
        if i >= self.scene.lights.len() {
            return;
        }
        let next = next_technique(self.options.technique_for(i));
        let over = (next != self.options.technique).then_some(next);
        self.options.set_technique_for(i, over);
        self.status = format!("light {i}: {next}");
    }

    /// The global technique's next value (lights without an override follow it).
    pub fn cycle_technique(&mut self) {
        self.options.technique = next_technique(self.options.technique);
        self.status = format!("technique: {}", self.options.technique);
    }

    pub fn cycle_view(&mut self) {
        let i = ViewMode::ALL
            .iter()
            .position(|m| *m == self.view)
            .unwrap_or(0);
        self.view = ViewMode::ALL[(i + 1) % ViewMode::ALL.len()];
    }

    /// Moves the walkthrough by `delta` steps (entering it at the first step).
    pub fn step_walkthrough(&mut self, delta: i64) {
        let last = self.steps.len().saturating_sub(1) as i64;
        let k = self
            .walkthrough
            .map_or(0, |k| k as i64 + delta)
            .clamp(0, last);
        self.walkthrough = Some(k as usize);
    }

    pub fn toggle(&mut self, t: Toggle, on: bool) {
        match t {
            Toggle::Volumes => self.overlays.volumes = on,
            Toggle::Silhouettes => self.overlays.silhouettes = on,
            Toggle::Texels => self.overlays.texel_grid = on,
            Toggle::Timings => self.show_timings = on,
            Toggle::Help => self.show_help = on,
            Toggle::Estimate => self.live_error.on = on,
        }
    }

    /// Starts recording the camera's poses into `file`, or stops and writes them.
    pub fn record(&mut self, file: Option<PathBuf>) -> Result<(), String> {
        if let Some((path, keys)) = self.recording.take() {
            std::fs::write(&path, path::to_text(&keys))
                .map_err(|e| format!("{}: {e}", path.display()))?;
            self.status = format!("recorded {} poses into {}", keys.len(), path.display());
            self.last_path = Some(path);
        }
        if let Some(f) = file {
            self.status = format!("recording into {}", f.display());
            self.recording = Some((f, Vec::new()));
        }
        Ok(())
    }

    pub fn replay(&mut self, file: PathBuf) -> Result<(), String> {
        let keys = path::read(&file).map_err(|e| e.to_string())?;
        self.status = format!("replaying {} poses of {}", keys.len(), file.display());
        self.replay = keys.into();
        self.last_path = Some(file);
        Ok(())
    }

    /// A numbered screenshot file in the working directory.
    pub fn next_screenshot(&mut self) -> PathBuf {
        self.screenshots += 1;
        PathBuf::from(format!("shadowlab-screenshot-{}.png", self.screenshots))
    }

    /// The first surface the view's centre looks at (exact ray cast), if any within 65536 units.
    pub fn view_point(&self) -> Option<glam::Vec3> {
        let reference = crate::truth::Reference::build(&self.scene);
        let dir = self.camera.forward().as_dvec3();
        let hit = reference.nearest_hit(self.camera.position.as_dvec3(), dir, 65536.0)?;
        Some((self.camera.position.as_dvec3() + dir * hit.distance).as_vec3())
    }

    /// Applies a panel edit to the scene.
    pub fn act(&mut self, action: Action) {
        use super::edit;
        use crate::scene::Light;
        let camera = self.camera;
        let target = self.view_point();
        let lights = self.scene.lights.len();
        let l = self.selected_light.min(lights.saturating_sub(1));
        match action {
            Action::LightToCamera if lights > 0 => {
                Arc::make_mut(&mut self.scene).lights[l].position = camera.position;
                self.status = format!("light {l} moved to the camera");
            }
            Action::AimLightAtView if lights > 0 => match target {
                Some(t) => {
                    edit::aim_light(&mut Arc::make_mut(&mut self.scene).lights[l], t);
                    self.status = format!("light {l} aimed at {:.0?}", t.to_array());
                }
                None => self.status = "nothing under the view's centre".into(),
            },
            Action::AddSpot | Action::AddOmni => {
                let n = self.scene.lights.len();
                let light = if action == Action::AddSpot {
                    let t = target.unwrap_or(camera.position + camera.forward() * 256.0);
                    Light::spot(&format!("spot{n}"), camera.position, t, 35.0, 1000.0)
                } else {
                    Light::omni(&format!("omni{n}"), camera.position, 600.0)
                };
                self.selected_light = edit::add_light(Arc::make_mut(&mut self.scene), light);
                self.status = format!("added light {}", self.selected_light);
            }
            Action::RemoveLight if lights > 0 => {
                edit::remove_light(Arc::make_mut(&mut self.scene), &mut self.options, l);
                self.selected_light = l.saturating_sub(1);
                self.status = format!("removed light {l}");
            }
            Action::PlaceModel | Action::CopyModel if !self.scene.models.is_empty() => {
                let Some(t) = target else {
                    self.status = "nothing under the view's centre".into();
                    return;
                };
                let m = self.selected_model.min(self.scene.models.len() - 1);
                let at = edit::standing_at(t, camera.yaw_deg + 180.0);
                let scene = Arc::make_mut(&mut self.scene);
                if action == Action::PlaceModel {
                    edit::move_model(scene, m, at);
                    self.status = format!("model {m} placed at {:.0?}", t.to_array());
                } else {
                    let (copy, e) = edit::copy_model(scene, m, at);
                    self.needs_upload |= e.needs_upload;
                    self.selected_model = copy;
                    self.status = format!("model {copy} added at {:.0?}", t.to_array());
                }
            }
            _ => self.status = "nothing to edit".into(),
        }
    }

    /// Runs the script until it has to wait for frames, a replay or the error job.
    pub fn run_script(&mut self) -> Result<(), String> {
        if self.wait > 0 {
            self.wait -= 1;
            return Ok(());
        }
        if !self.replay.is_empty() {
            return Ok(());
        }
        if self.error_blocks {
            if self.current_error().is_none() {
                return Ok(());
            }
            self.error_blocks = false;
        }
        if let Some((target, frames_left)) = self.wait_sampled {
            let sampled = self.live_error.sampled_frames();
            if sampled < target {
                if frames_left == 0 {
                    return Err(format!(
                        "`sampled`: after {SAMPLED_FRAME_LIMIT} frames the live error is still \
                         {} sampled frames short (is estimate.budget 0?)",
                        target - sampled
                    ));
                }
                self.wait_sampled = Some((target, frames_left - 1));
                return Ok(());
            }
            self.wait_sampled = None;
        }
        while let Some(c) = self.script.pop_front() {
            match c {
                Command::Wait(n) => {
                    self.wait = n.saturating_sub(1);
                    return Ok(());
                }
                Command::Sampled(n) => {
                    if !self.live_error.on {
                        return Err("`sampled` needs the live error: `overlay estimate on`".into());
                    }
                    let target = self.live_error.sampled_frames() + n as u64;
                    self.wait_sampled = Some((target, SAMPLED_FRAME_LIMIT));
                    return Ok(());
                }
                Command::Set(a) => {
                    let mut o = self.options.clone();
                    o.set_assignment(&a).map_err(|e| e.to_string())?;
                    o.validate().map_err(|e| e.to_string())?;
                    self.options = o;
                }
                Command::LightTechnique(i, t) => {
                    if i >= self.scene.lights.len() {
                        return Err(format!(
                            "light {i}: the scene has {}",
                            self.scene.lights.len()
                        ));
                    }
                    self.options.set_technique_for(i, t);
                }
                Command::Select(i) => {
                    if i >= self.scene.lights.len() {
                        return Err(format!(
                            "select {i}: the scene has {} lights",
                            self.scene.lights.len()
                        ));
                    }
                    self.selected_light = i;
                }
                Command::View(v) => self.view = v,
                // Up to six faces, or as many frusta as `shadow_map.max_frusta` allows; the view
                // shows the last a light has when asked for more.
                Command::Face(f) => self.face = f.min(63),
                Command::Overlay(t, on) => self.toggle(t, on),
                Command::Walkthrough(k) => {
                    self.walkthrough = k.map(|k| k.min(self.steps.len().saturating_sub(1)))
                }
                Command::Camera([x, y, z, yaw, pitch]) => {
                    self.camera.position = glam::Vec3::new(x, y, z);
                    self.camera.yaw_deg = yaw;
                    self.camera.pitch_deg = pitch.clamp(-89.9, 89.9);
                }
                Command::Replay(f) => {
                    self.replay(f)?;
                    return Ok(());
                }
                Command::Record(f) => self.record(f)?,
                Command::Error => {
                    self.view = ViewMode::Error;
                    self.error_blocks = true;
                    return Ok(());
                }
                // Files show this frame as the commands so far made it: later commands wait
                // for the next frame.
                Command::Screenshot(f) => {
                    self.pending.push(Pending::Screenshot(f));
                    return Ok(());
                }
                Command::Frame(f) => {
                    self.pending.push(Pending::Frame(f));
                    return Ok(());
                }
                Command::Quit => {
                    self.quit = true;
                    return Ok(());
                }
                Command::Play(on) => self.clock.playing = on,
                Command::Time(t) => {
                    self.clock.time = t;
                    self.advance_motion(0.0, 0);
                }
                Command::Step(n) => self.advance_motion(0.0, n),
                Command::Grab(on) => {
                    if on != self.grabbed.is_some() {
                        self.toggle_grab();
                    }
                }
            }
        }
        Ok(())
    }

    /// Whether a script still has work (the window then renders continuously).
    pub fn scripted(&self) -> bool {
        !self.script.is_empty()
            || self.wait > 0
            || !self.replay.is_empty()
            || self.error_blocks
            || self.wait_sampled.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;
    use crate::viewer::script;

    fn state(script_text: &str) -> ViewerState {
        // Unshadowed at first, so that the script's `set technique` is seen to act.
        let options = Options {
            technique: Technique::None,
            ..Options::default()
        };
        ViewerState::new(
            builtin::default_scene(),
            options,
            script::parse(script_text).unwrap(),
        )
    }

    #[test]
    fn scripts_act_frame_by_frame() {
        let mut s = state(
            "set technique=shadow_map\nwait 2\nlight 1 shadow_volume\nscreenshot a.png\nquit",
        );
        s.run_script().unwrap(); // the first frame renders before the script starts
        assert_eq!(s.options.technique, Technique::None);
        s.run_script().unwrap();
        assert_eq!(s.options.technique, Technique::ShadowMap);
        s.run_script().unwrap(); // the second frame of `wait 2`
        assert!(!s.quit);
        s.run_script().unwrap();
        assert_eq!(s.options.technique_for(1), Technique::ShadowVolume);
        assert_eq!(s.pending, vec![Pending::Screenshot("a.png".into())]);
        assert!(!s.quit, "the screenshot's frame comes first");
        s.run_script().unwrap();
        assert!(s.quit);
    }

    #[test]
    fn scripts_step_the_motion_and_a_grabbed_light_follows_the_camera() {
        use crate::scene::motion::{LightMotion, LightPath};
        let mut scene = builtin::default_scene();
        let start = scene.lights[0].position;
        scene.motion.lights.push(LightMotion {
            light: 0,
            path: LightPath::Orbit {
                centre: start - glam::Vec3::X * 50.0,
                start,
                period: 4.0,
            },
            aim: None,
            color: scene.lights[0].color,
        });
        let mut s = ViewerState::new(
            scene,
            Options::default(),
            script::parse("play off\nstep 4\nstep -2\ngrab on\nwait 1\ncamera 0 0 100 0 0\n")
                .unwrap(),
        );
        s.run_script().unwrap(); // the first frame
        s.run_script().unwrap();
        assert!(!s.clock.playing);
        assert!((s.clock.time - 2.0 * MotionClock::STEP).abs() < 1e-12);
        let moved = s.scene.lights[0].position;
        assert!(moved.distance(start) > 1.0, "the light orbits");
        // Grabbed, the light keeps its offset from the camera as the script moves it.
        let offset = moved - s.camera.position;
        s.run_script().unwrap(); // `wait 1`
        s.run_script().unwrap(); // `camera`
        assert_eq!(s.camera.position, glam::Vec3::new(0.0, 0.0, 100.0));
        s.advance_camera(0.0);
        assert!((s.scene.lights[0].position - (s.camera.position + offset)).length() < 1e-3);
        // Paused, time does not run.
        s.advance_motion(1.0, 0);
        assert!((s.clock.time - 2.0 * MotionClock::STEP).abs() < 1e-12);
    }

    #[test]
    fn bad_script_values_are_errors() {
        let mut s = state("light 7 shadow_map");
        s.run_script().unwrap();
        assert!(s.run_script().unwrap_err().contains("light 7"));
        let mut s = state("set shadow_map.size=3");
        s.run_script().unwrap();
        assert!(s.run_script().is_err());
    }

    #[test]
    fn technique_keys_cycle_and_drop_redundant_overrides() {
        let mut s = state("");
        s.options.technique = Technique::ShadowMap;
        s.cycle_light_technique(0);
        assert_eq!(s.options.lighting.techniques, "0:psm");
        // tsm, shadow_volume, hybrid, subdivision, auto, none.
        for _ in 0..6 {
            s.cycle_light_technique(0);
        }
        assert_eq!(s.options.lighting.techniques, "0:none");
        s.cycle_light_technique(0);
        assert_eq!(s.options.technique_for(0), Technique::ShadowMap);
        assert_eq!(s.options.lighting.techniques, "");
    }

    #[test]
    fn the_walkthrough_stays_within_the_frame_steps() {
        let mut s = state("");
        let step = |kind| Step {
            kind,
            light: None,
            face: None,
            technique: None,
        };
        s.frame_done(
            1.0,
            &[
                step(crate::frame::StepKind::Base),
                step(crate::frame::StepKind::Lit),
            ],
        );
        s.step_walkthrough(5);
        assert_eq!(s.walkthrough, Some(0));
        s.step_walkthrough(5);
        assert_eq!(s.walkthrough, Some(1));
        s.step_walkthrough(-3);
        assert_eq!(s.walkthrough, Some(0));
        assert_eq!(s.request().stop_after, Some(0));
    }

    #[test]
    fn the_frame_key_follows_camera_options_and_lights() {
        let mut s = state("");
        let k = s.frame_key();
        s.camera.yaw_deg += 1.0;
        assert_ne!(s.frame_key(), k);
        let k = s.frame_key();
        s.options.shadow_map.size = 256;
        assert_ne!(s.frame_key(), k);
        let k = s.frame_key();
        Arc::make_mut(&mut s.scene).lights[0].position.x += 1.0;
        assert_ne!(s.frame_key(), k);
    }
}
