//! Round-robin timing: every configuration and its shadows-off baseline on a renderer of its
//! own, one frame of each in turn, a group of renderers at a time within `memory_mb`.

use super::*;

impl Bench<'_> {
    /// Every configuration and every baseline they need, each on a renderer of its own sharing
    /// this one's GL context, warmed up, then timed one frame each in turn (the order rotating
    /// frame by frame), then broken down pass by pass. Keyed by `options_key`. With
    /// `memory_mb`, the renderers are made a group at a time, each group's maps within it
    /// ([`Self::groups`]).
    pub(super) fn measure_interleaved(
        &mut self,
        configs: &[BenchConfig],
        bar: &ProgressBar,
    ) -> Result<HashMap<String, Measured>, RenderError> {
        let mut timed: Vec<(String, Options)> = Vec::new();
        for c in configs {
            let mut wanted = vec![c.options.clone()];
            if c.options.technique != Technique::None {
                wanted.push(Self::shadows_off(&c.options));
            }
            for o in wanted {
                let key = options_key(&o);
                if !timed.iter().any(|(k, _)| *k == key) {
                    timed.push((key, o));
                }
            }
        }
        let groups = self.groups(&timed);
        let mut out = HashMap::new();
        for (g, group) in groups.iter().enumerate() {
            bar.set_message(match groups.len() {
                1 => format!("{} option sets, round-robin", group.len()),
                n => format!(
                    "{} option sets, round-robin, group {} of {n} (--memory-mb)",
                    group.len(),
                    g + 1
                ),
            });
            let members: Vec<(String, Options)> = group.iter().map(|&i| timed[i].clone()).collect();
            out.extend(self.measure_group(members, g)?);
        }
        Ok(out)
    }

    /// `timed` split into groups whose renderers fit `memory_mb` together, in order; a
    /// configuration stays with the baseline that follows it. A renderer holds what the same
    /// options held after their frames in an earlier bench of the scene (maps, volumes and
    /// fragments: `tune`'s rungs measured every finalist), else the first frame's maps,
    /// within `shadow_map.budget_mb` ([`crate::plan::map_memory`]); one that alone holds more
    /// has a group of its own. One group without `memory_mb`.
    fn groups(&self, timed: &[(String, Options)]) -> Vec<Vec<usize>> {
        let Some(limit) = self.settings.memory_mb else {
            return vec![(0..timed.len()).collect()];
        };
        let limit = (f64::from(limit) * 1048576.0) as u64;
        let scene = &self.scene;
        let camera = self.settings.camera(scene, 0);
        let holds = |o: &Options| -> u64 {
            if o.technique == Technique::None {
                return 0;
            }
            if let Some(&bytes) = self.held.get(&error::error_key(o)) {
                return bytes;
            }
            let bytes = crate::plan::Plan::build_at(scene, &camera, o)
                .stats
                .map_bytes;
            crate::plan::map_memory::budget_bytes(&o.shadow_map).map_or(bytes, |b| bytes.min(b))
        };
        let mut groups: Vec<Vec<usize>> = Vec::new();
        let mut held = 0;
        for (i, (_, o)) in timed.iter().enumerate() {
            let bytes = holds(o);
            let fits = held + bytes <= limit || o.technique == Technique::None;
            match groups.last_mut() {
                Some(g) if fits => g.push(i),
                _ => {
                    groups.push(vec![i]);
                    held = 0;
                }
            }
            held += bytes;
        }
        groups
    }

    /// Group `group` of option sets measured round-robin, each on a renderer of its own
    /// (dropped at the end, with what it kept).
    fn measure_group(
        &mut self,
        timed: Vec<(String, Options)>,
        group: usize,
    ) -> Result<HashMap<String, Measured>, RenderError> {
        let (scene, settings, choices) = (&mut self.scene, &self.settings, &self.choices);
        let mut renderers = Vec::with_capacity(timed.len());
        let mut prepared = Vec::with_capacity(timed.len());
        for (key, o) in &timed {
            let mut r = self.renderer.sibling_with_scene(o.width, o.height, scene)?;
            settings.pose(scene, 0);
            prepared.push(r.prepare(scene, o)?);
            // Frames that follow a sampled run's choices need no teaching.
            let follows = choices.get(key);
            if follows.is_none() {
                let reference = self.view.reference(scene);
                error::learn_at_start(&mut r, (scene, settings), o, reference)?;
            }
            let first = settings.frame(scene, (&mut r, follows), 0);
            for _ in 0..settings.warmup {
                r.render_at(scene, &first, o, FrameRequest::default())?;
            }
            renderers.push(r);
        }
        let mut frames: Vec<Vec<Timed>> = timed.iter().map(|_| Vec::new()).collect();
        for i in 0..settings.frames.max(1) {
            for k in 0..timed.len() {
                let j = (k + i) % timed.len();
                let ms: f64 = frames[j].iter().map(|t| t.ms).sum();
                if settings.enough(scene, frames[j].len(), ms) {
                    continue;
                }
                // Every configuration draws the same posed frame.
                let follows = (&mut renderers[j], choices.get(&timed[j].0));
                let camera = settings.frame(scene, follows, i);
                frames[j].push(time_frame(&mut renderers[j], scene, &camera, &timed[j].1)?);
            }
        }
        let mut out = HashMap::new();
        for ((((key, o), r), f), p) in timed
            .into_iter()
            .zip(&mut renderers)
            .zip(&frames)
            .zip(prepared)
        {
            let mut m = pass_breakdown((r, choices.get(&key)), scene, settings, &o, f)?;
            m.prepared = p;
            m.held_bytes = r.held().bytes();
            m.group = Some(group);
            self.held.insert(error::error_key(&o), m.held_bytes);
            out.insert(key, m);
        }
        Ok(out)
    }
}
