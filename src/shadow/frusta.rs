//! Several frusta per omni light (Forsyth's "multiple frustums"): instead of six 90° faces of
//! one size, maps fitted around the receivers in view, each with the texels its receivers' size
//! on screen asks for, within one budget of texels for the light.
//!
//! Each frustum is a rectangle of one cube face's image plane (eye x and y over the distance
//! along the face's axis; the whole face is [-1, 1]²). So a frustum spans at most 90° (Forsyth:
//! at most about 120°), a fragment finds its frustum as it finds its face and then by rectangle,
//! and the rectangles of one face never overlap. A receiver across faces is drawn into each
//! (his "large or close objects drawn into several").
//!
//! The rectangles come from a quadtree per face, split best saving first. A node's map needs
//! (its densest receiver's texels per plane unit × the longer side of the rectangle its
//! receivers cover)² texels; scaling every map to the budget then gives every receiver the same
//! share of what it asks for, so the fewer texels the nodes need in all, the larger that share.
//! A split is taken where the four quadrants need clearly fewer texels than their parent, and
//! never beyond the count of frusta allowed (each is one more depth and lit pass). GL-free.

use crate::geometry::Aabb;
use crate::geometry::clip::clip_box;
use crate::geometry::projection::cube_face_view;
use crate::scene::Light;
use crate::shadow::views::{FacePart, MIN_NEAR, Rect, ShadowView, ViewKind, near_far};
use glam::{Mat4, Vec2, Vec3, Vec4};

/// A split is taken only when the quadrants need at most this share of their parent's texels
/// (less saving is not worth a pass).
pub const SPLIT_GAIN: f64 = 0.75;
/// Texels of a frustum's map beyond its rectangle on each side: room for a 5x5 filter
/// (`shadow_map.pcf_size` 5) and a texel of rounding.
pub const MARGIN_TEXELS: u32 = 1;
/// Quadtree depth: a frustum is at least 1/2⁴ of a face across.
pub const MAX_DEPTH: u32 = 4;

/// What one receiver asks for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Need {
    pub bounds: Aabb,
    /// Map texels per world unit its size on screen asks for (about the screen pixels one world
    /// unit covers where it is).
    pub texels_per_unit: f32,
    /// How many screen pixels its shadows' errors can spread over: its size on screen, in
    /// pixels (the weight of its share of the budget).
    pub weight: f32,
}

/// Where the receivers are seen from, for [`receiver_needs`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Eye {
    pub position: Vec3,
    /// Screen pixels per world unit at distance 1 (half the frame's height over tan(fovy/2)).
    pub pixels: f32,
    /// Nothing is nearer than this (the camera's near plane).
    pub near: f32,
    /// The frame's larger side: no receiver is larger on screen.
    pub screen: f32,
}

/// Times a receiver's box is halved at most for [`receiver_needs`] (up to 2⁴ pieces).
pub const NEED_SPLITS: u32 = 4;

/// What a receiver with box `bounds` asks for, seen from `eye`: the pixels per unit at its
/// nearest point, weighted by its size on screen. A box longer than its distance from the eye
/// is halved along its longest side first (up to [`NEED_SPLITS`] times), so that a floor
/// passing under the camera asks for many texels only where it is near.
pub fn receiver_needs(bounds: Aabb, eye: &Eye, out: &mut Vec<Need>) {
    fn split(b: Aabb, eye: &Eye, depth: u32, out: &mut Vec<Need>) {
        let p = eye.position;
        let distance = p.clamp(b.min, b.max).distance(p).max(eye.near);
        let extent = b.max - b.min;
        let long = extent.max_element();
        if depth < NEED_SPLITS && long > distance {
            let axis = if extent.x == long {
                0
            } else if extent.y == long {
                1
            } else {
                2
            };
            let mid = (b.min[axis] + b.max[axis]) * 0.5;
            let (mut lo, mut hi) = (b, b);
            lo.max[axis] = mid;
            hi.min[axis] = mid;
            split(lo, eye, depth + 1, out);
            split(hi, eye, depth + 1, out);
            return;
        }
        let texels_per_unit = eye.pixels / distance;
        out.push(Need {
            bounds: b,
            texels_per_unit,
            weight: (long * texels_per_unit).min(eye.screen),
        });
    }
    split(bounds, eye, 0, out);
}

/// How many texels a light's frusta may have in all, and in how many maps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Budget {
    /// Texels of all maps together (six faces of n² texels: 6n²).
    pub texels: u64,
    pub max_frusta: usize,
    pub min_size: u32,
    pub max_size: u32,
}

/// One chosen frustum: rectangle `rect` of cube face `face` (the
/// [`crate::shadow::views::major_face`] numbering) and its square map's size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaceFrustum {
    pub face: usize,
    /// What the receivers cover of the cell: the map's extent.
    pub rect: Rect,
    /// The quadtree cell it lights (the whole face when the face is not split).
    pub cell: Rect,
    pub size: u32,
}

impl FaceFrustum {
    /// World to eye: the face's own view.
    pub fn view(&self, light: Vec3) -> Mat4 {
        cube_face_view(light, self.face)
    }

    /// The off-centre frustum over the rectangle (glFrustum's), widened by `MARGIN_TEXELS` on
    /// each side so that filters reading around a texel at the rectangle's edge read receivers,
    /// not the clamped edge.
    pub fn projection(&self, near: f32, far: f32) -> Mat4 {
        let n = self.size.max(2 * MARGIN_TEXELS + 1) as f32;
        // The rectangle spans n - 2m texels of the widened map.
        let m = (self.rect.max - self.rect.min) * MARGIN_TEXELS as f32
            / (n - 2.0 * MARGIN_TEXELS as f32);
        let (lo, hi) = ((self.rect.min - m) * near, (self.rect.max + m) * near);
        Mat4::frustum_rh_gl(lo.x, hi.x, lo.y, hi.y, near, far)
    }

    /// Map texels per world unit across the view at `distance` along the face's axis.
    pub fn texels_per_unit(&self, distance: f32) -> f32 {
        self.size as f32 / (self.rect.side().max(f32::MIN_POSITIVE) * distance)
    }
}

/// A receiver's footprint on one face.
#[derive(Debug, Clone, Copy)]
struct Mark {
    rect: Rect,
    /// Texels per plane unit it asks for.
    density: f32,
    weight: f32,
}

/// Where `p` (eye space of a face view) falls on the face's image plane.
pub fn on_plane(p: Vec3) -> Vec2 {
    Vec2::new(p.x, p.y) / -p.z
}

/// Eye space looks down -z: inside a face, |x| and |y| are at most -z, and beyond the near plane.
const FACE_PLANES: [Vec4; 5] = [
    Vec4::new(-1.0, 0.0, -1.0, 0.0),
    Vec4::new(1.0, 0.0, -1.0, 0.0),
    Vec4::new(0.0, -1.0, -1.0, 0.0),
    Vec4::new(0.0, 1.0, -1.0, 0.0),
    Vec4::new(0.0, 0.0, -1.0, -MIN_NEAR),
];

/// What the part of `bounds` inside a face's pyramid (eye space `view`) and beyond the near
/// plane covers of the face's image plane, and its mean distance along the face's axis; None
/// where no part is. `points` is scratch space.
fn footprint_in(view: &Mat4, bounds: &Aabb, points: &mut Vec<Vec3>) -> Option<(Rect, f32)> {
    points.clear();
    // A face view permutes the axes, so the box stays a box in eye space.
    clip_box(&bounds.transformed(view), &FACE_PLANES, points);
    if points.is_empty() {
        return None;
    }
    let depth = points.iter().map(|p| -p.z).sum::<f32>() / points.len() as f32;
    let mut rect = Rect {
        min: Vec2::INFINITY,
        max: Vec2::NEG_INFINITY,
    };
    for p in points.iter() {
        let q = on_plane(*p).clamp(Rect::FACE.min, Rect::FACE.max);
        rect.min = rect.min.min(q);
        rect.max = rect.max.max(q);
    }
    Some((rect, depth))
}

/// What `bounds` covers of face `face` of an omni light at `light` (None: nothing beyond the
/// near plane): whether a frustum's cell holds part of a receiver.
pub fn footprint(light: Vec3, face: usize, bounds: &Aabb) -> Option<Rect> {
    footprint_in(&cube_face_view(light, face), bounds, &mut Vec::new()).map(|(r, _)| r)
}

/// Each face's marks: each receiver's footprint, asking for its texels per unit times its mean
/// distance (a world unit at distance d spans 1/d of the plane).
fn marks(light: Vec3, needs: &[Need]) -> [Vec<Mark>; 6] {
    std::array::from_fn(|face| {
        let view = cube_face_view(light, face);
        let mut points = Vec::new();
        needs
            .iter()
            .filter_map(|n| {
                let (rect, depth) = footprint_in(&view, &n.bounds, &mut points)?;
                Some(Mark {
                    rect,
                    density: n.texels_per_unit.max(0.0) * depth,
                    weight: n.weight.max(0.0),
                })
            })
            .collect()
    })
}

/// A quadtree node with receivers: `quad` its cell, `rect` what they cover of it.
#[derive(Debug, Clone)]
struct Node {
    face: usize,
    depth: u32,
    quad: Rect,
    rect: Rect,
    density: f32,
    marks: Vec<usize>,
}

impl Node {
    /// The node of `quad` over those of `of` that reach into it (None: none do).
    fn fit(face: usize, depth: u32, quad: Rect, marks: &[Mark], of: &[usize]) -> Option<Node> {
        let mut node: Option<Node> = None;
        for &i in of {
            let Some(r) = marks[i].rect.intersection(&quad) else {
                continue;
            };
            let n = node.get_or_insert_with(|| Node {
                face,
                depth,
                quad,
                rect: r,
                density: 0.0,
                marks: Vec::new(),
            });
            n.rect = n.rect.union(&r);
            n.density = n.density.max(marks[i].density);
            n.marks.push(i);
        }
        node
    }

    /// Texels its map needs to give each of its receivers what it asks for.
    fn cost(&self) -> f64 {
        (self.density as f64 * self.rect.side() as f64).powi(2)
    }

    /// Its map's side relative to the others'. A receiver's wrong pixels along a shadow's edge
    /// are about its size on screen (`weight`) times the screen pixels per map texel (its
    /// density × the rectangle's side / the map's side): the node's error is `c / size` with
    /// `c` = side × Σ weight × density. Sizes minimising Σ c / size at a fixed Σ size² go as
    /// c^(1/3): a receiver asking for far more than the rest (one at the camera) gets more, but
    /// does not starve them.
    fn share(&self, marks: &[Mark]) -> f64 {
        let c: f64 = self
            .marks
            .iter()
            .map(|&i| marks[i].weight as f64 * marks[i].density as f64)
            .sum::<f64>()
            * self.rect.side() as f64;
        c.cbrt()
    }

    fn split(&self, marks: &[Mark]) -> Vec<Node> {
        self.quad
            .quadrants()
            .into_iter()
            .filter_map(|q| Node::fit(self.face, self.depth + 1, q, marks, &self.marks))
            .collect()
    }
}

/// The frusta for an omni light at `light` over the receivers `needs`, within `budget`.
/// Empty when no receiver lies beyond the near plane.
pub fn choose(light: Vec3, needs: &[Need], budget: &Budget) -> Vec<FaceFrustum> {
    let marks = marks(light, needs);
    let mut nodes: Vec<Node> = (0..6)
        .filter_map(|face| {
            let all: Vec<usize> = (0..marks[face].len()).collect();
            Node::fit(face, 0, Rect::FACE, &marks[face], &all)
        })
        .collect();
    let max = budget.max_frusta.max(nodes.len());
    loop {
        let mut best: Option<(usize, f64, Vec<Node>)> = None;
        for (i, n) in nodes.iter().enumerate() {
            if n.depth >= MAX_DEPTH {
                continue;
            }
            let children = n.split(&marks[n.face]);
            if nodes.len() - 1 + children.len() > max {
                continue;
            }
            let parent = n.cost();
            let saving = parent - children.iter().map(Node::cost).sum::<f64>();
            if saving > (1.0 - SPLIT_GAIN) * parent && best.as_ref().is_none_or(|b| saving > b.1) {
                best = Some((i, saving, children));
            }
        }
        let Some((i, _, children)) = best else { break };
        nodes.swap_remove(i);
        nodes.extend(children);
    }
    nodes.sort_by_key(|n| n.face);
    let raw: Vec<f64> = nodes.iter().map(|n| n.share(&marks[n.face])).collect();
    let sizes = fit_sizes(&raw, budget);
    nodes
        .iter()
        .zip(sizes)
        .map(|(n, size)| FaceFrustum {
            face: n.face,
            rect: n.rect,
            cell: n.quad,
            size,
        })
        .collect()
}

/// Whether frusta chosen earlier for a light at `light` still serve `needs`: every receiver's
/// footprint on each face it reaches meets a frustum's cell there, and what it covers of each
/// such cell lies in that frustum's rectangle (up to `slack` of the plane). A static light keeps
/// its frusta (and so its maps) while they do (Forsyth: persistent frusta for static lights).
pub fn still_cover(light: Vec3, kept: &[FaceFrustum], needs: &[Need], slack: f32) -> bool {
    let marks = marks(light, needs);
    marks.iter().enumerate().all(|(face, marks)| {
        let own: Vec<&FaceFrustum> = kept.iter().filter(|f| f.face == face).collect();
        marks.iter().all(|m| {
            let mut met = false;
            for f in &own {
                let Some(part) = m.rect.intersection(&f.cell) else {
                    continue;
                };
                met = true;
                if (part.min - f.rect.min).min_element() < -slack
                    || (f.rect.max - part.max).min_element() < -slack
                {
                    return false;
                }
            }
            met
        })
    })
}

/// The shadow views of `frusta` around an omni `light`: each its face's view and the
/// off-centre projection over its rectangle, near and far fitted as for the whole face (thesis
/// 2.2.2; `casters` are the casters' world bounds).
pub fn frustum_views(
    light: &Light,
    frusta: &[FaceFrustum],
    casters: &[Aabb],
    fit: bool,
) -> Vec<ShadowView> {
    let mut fitted: [Option<(f32, f32)>; 6] = [None; 6];
    frusta
        .iter()
        .map(|f| {
            let view = f.view(light.position);
            let (near, far) =
                *fitted[f.face].get_or_insert_with(|| near_far(&view, light, casters, fit));
            ShadowView {
                kind: ViewKind::Face(f.face),
                view,
                projection: f.projection(near, far),
                near,
                far,
                depth_view_proj: None,
                part: Some(FacePart {
                    size: f.size,
                    cell: f.cell,
                }),
                size: f.size,
            }
        })
        .collect()
}

/// Sizes proportional to `raw` whose squares sum to the budget's texels, within its bounds:
/// those held at the largest size give their share to the rest.
fn fit_sizes(raw: &[f64], budget: &Budget) -> Vec<u32> {
    let (lo, hi) = (budget.min_size.max(1) as f64, budget.max_size.max(1) as f64);
    let mut capped = vec![false; raw.len()];
    let mut scale = 0.0;
    for _ in 0..=raw.len() {
        let held: f64 = capped.iter().filter(|c| **c).count() as f64 * hi * hi;
        let free: f64 = raw
            .iter()
            .zip(&capped)
            .filter(|(_, c)| !**c)
            .map(|(r, _)| r * r)
            .sum();
        scale = if free > 0.0 {
            ((budget.texels as f64 - held).max(0.0) / free).sqrt()
        } else {
            0.0
        };
        let mut changed = false;
        for (r, c) in raw.iter().zip(capped.iter_mut()) {
            if !*c && r * scale > hi {
                *c = true;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    raw.iter()
        .zip(&capped)
        .map(|(r, c)| if *c { hi } else { (r * scale).floor().clamp(lo, hi) } as u32)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shadow::views::major_face;

    fn cube(c: Vec3, h: f32) -> Aabb {
        Aabb {
            min: c - h,
            max: c + h,
        }
    }

    fn budget(n: u32) -> Budget {
        Budget {
            texels: 6 * (n as u64).pow(2),
            max_frusta: 12,
            min_size: 16,
            max_size: 4096,
        }
    }

    /// Walls all around a light at the origin, 50 units away, each asking for 1 texel per unit.
    fn room() -> Vec<Need> {
        (0..6)
            .map(|f| {
                let axis = crate::plan::cull::face_axes(f).0;
                let c = axis * 50.0;
                let h = Vec3::splat(60.0) - axis.abs() * 59.0;
                Need {
                    bounds: Aabb {
                        min: c - h,
                        max: c + h,
                    },
                    texels_per_unit: 1.0,
                    weight: 100.0,
                }
            })
            .collect()
    }

    fn texels(f: &[FaceFrustum]) -> u64 {
        f.iter().map(|f| (f.size as u64).pow(2)).sum()
    }

    #[test]
    fn one_small_receiver_gets_one_tight_frustum_with_far_more_texels_per_unit() {
        let light = Vec3::ZERO;
        let need = Need {
            bounds: cube(Vec3::new(100.0, 10.0, -5.0), 5.0),
            texels_per_unit: 2.0,
            weight: 20.0,
        };
        let f = choose(light, &[need], &budget(512));
        assert_eq!(f.len(), 1, "{f:?}");
        assert_eq!(f[0].face, 0);
        // 10 units across at 95-105 units: about 0.1 of the plane, not the face's 2.
        assert!(f[0].rect.side() < 0.15, "{:?}", f[0].rect);
        // A 512 face gives 512 / (2 · 100) = 2.56 texels per unit at distance 100.
        let whole = FaceFrustum {
            face: 0,
            rect: Rect::FACE,
            cell: Rect::FACE,
            size: 512,
        };
        let (ours, face) = (f[0].texels_per_unit(100.0), whole.texels_per_unit(100.0));
        assert!(ours > 20.0 * face, "{ours} texels per unit against {face}");
        assert!(texels(&f) <= budget(512).texels);
    }

    /// Walls all around the light, asking for the same everywhere: nothing to gain from
    /// splitting, so the six faces stay, each whole.
    #[test]
    fn a_room_asking_for_the_same_everywhere_keeps_the_six_faces() {
        let light = Vec3::ZERO;
        let walls = room();
        let f = choose(light, &walls, &budget(256));
        assert_eq!(f.len(), 6, "{f:?}");
        for (i, f) in f.iter().enumerate() {
            assert_eq!(f.face, i);
            assert_eq!(f.rect, Rect::FACE);
            assert!(f.size.abs_diff(256) <= 1, "{f:?}");
        }
    }

    /// Forsyth's duelling frusta: the camera looks at the light, so the receivers near the
    /// camera (far from the light) ask for many texels per unit and those near the light for
    /// few. One face per direction gives the near ones what the whole face has; the frusta give
    /// them their own map.
    #[test]
    fn duelling_frusta_give_the_receiver_near_the_camera_its_own_dense_map() {
        let light = Vec3::ZERO;
        let mut needs = vec![Need {
            // Near the camera: 200 units out along -X, asking for 8 texels per unit.
            bounds: cube(
                Vec3::new(-200.0, 0.0, 0.0) + Vec3::new(0.0, 30.0, 20.0),
                4.0,
            ),
            texels_per_unit: 8.0,
            weight: 64.0,
        }];
        // The light's surroundings, far from the camera: a floor under it, asking for little.
        needs.push(Need {
            bounds: Aabb {
                min: Vec3::new(-150.0, -150.0, -40.0),
                max: Vec3::new(150.0, 150.0, -38.0),
            },
            texels_per_unit: 0.25,
            weight: 75.0,
        });
        let f = choose(light, &needs, &budget(512));
        assert!(texels(&f) <= budget(512).texels);
        let p = Vec3::new(-200.0, 30.0, 20.0);
        let face = major_face(p);
        let own = f
            .iter()
            .find(|f| {
                f.face == face && f.rect.contains(on_plane(f.view(light).transform_point3(p)))
            })
            .expect("the near receiver is in a frustum");
        let one_face = FaceFrustum {
            face,
            rect: Rect::FACE,
            cell: Rect::FACE,
            size: 512,
        };
        let (ours, faces) = (own.texels_per_unit(200.0), one_face.texels_per_unit(200.0));
        assert!(
            ours > 8.0 * faces,
            "{ours} texels per unit against the face's {faces}"
        );
    }

    /// Any scene: every point of a receiver's box beyond the near plane lies in a frustum of its face, the rectangles
    /// of a face do not overlap, and the count and the budget hold.
    #[test]
    fn frusta_cover_every_receiver_without_overlap_within_the_budget() {
        let mut rng = fastrand::Rng::with_seed(7);
        let mut split = 0;
        for _ in 0..200 {
            let light = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 100.0;
            let needs: Vec<Need> = (0..rng.usize(1..40))
                .map(|_| {
                    let c = light + (Vec3::new(rng.f32(), rng.f32(), rng.f32()) - 0.5) * 400.0;
                    let h = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 10.0 + 0.5;
                    Need {
                        bounds: Aabb {
                            min: c - h,
                            max: c + h,
                        },
                        texels_per_unit: 0.1 + rng.f32().powi(3) * 20.0,
                        weight: rng.f32() * 200.0,
                    }
                })
                .collect();
            let b = budget(256);
            let f = choose(light, &needs, &b);
            assert!(f.len() <= b.max_frusta.max(6), "{} frusta", f.len());
            split += usize::from(f.windows(2).any(|w| w[0].face == w[1].face));
            assert!(
                f.iter().all(|f| f.size >= b.min_size)
                    && texels(&f) <= b.texels + f.len() as u64 * (b.min_size as u64).pow(2),
                "{} texels of {}",
                texels(&f),
                b.texels
            );
            for (i, a) in f.iter().enumerate() {
                for c in &f[i + 1..] {
                    assert!(a.face != c.face || !a.rect.overlaps(&c.rect), "{a:?} {c:?}");
                }
            }
            for n in &needs {
                let (lo, size) = (n.bounds.min, n.bounds.max - n.bounds.min);
                let inner: Vec<Vec3> = (0..16)
                    .map(|_| lo + size * Vec3::new(rng.f32(), rng.f32(), rng.f32()))
                    .collect();
                for p in n.bounds.corners().into_iter().chain(inner) {
                    let d = p - light;
                    let face = major_face(d);
                    let along = crate::plan::cull::face_axes(face).0.dot(d);
                    if along < MIN_NEAR * 1.01 {
                        continue;
                    }
                    let q = on_plane(cube_face_view(light, face).transform_point3(p));
                    // Within a hair: the test projects the corner another way than the chooser.
                    let inside =
                        |r: &Rect| (r.min - 1e-4).cmple(q).all() && q.cmple(r.max + 1e-4).all();
                    assert!(
                        f.iter().any(|f| f.face == face && inside(&f.rect)),
                        "corner {p:?} (face {face}, {q:?}) in no frustum: {f:?}"
                    );
                }
            }
        }
        // The cover is tested where faces were split, not only on whole faces.
        assert!(split > 50, "faces split in only {split} of 200 scenes");
    }

    /// A floor passing under the camera asks for many texels where it is near and few far off.
    #[test]
    fn a_long_floor_asks_for_more_near_the_camera() {
        let eye = Eye {
            position: Vec3::new(0.0, 0.0, 50.0),
            pixels: 400.0,
            near: 4.0,
            screen: 640.0,
        };
        let floor = Aabb {
            min: Vec3::new(-2000.0, -100.0, 0.0),
            max: Vec3::new(2000.0, 100.0, 0.0),
        };
        let mut needs = Vec::new();
        receiver_needs(floor, &eye, &mut needs);
        // Halved where longer than its distance: 8 pieces, the far ones left whole.
        assert!(
            needs.len() > 4 && needs.len() <= 1 << NEED_SPLITS,
            "{needs:?}"
        );
        let near = needs
            .iter()
            .find(|n| n.bounds.min.x <= 0.0 && n.bounds.max.x >= 0.0);
        let far = needs.iter().find(|n| n.bounds.min.x == -2000.0);
        let (near, far) = (near.unwrap(), far.unwrap());
        // 50 units below the eye against 1000 units away.
        assert!((near.texels_per_unit - 8.0).abs() < 1e-3, "{near:?}");
        assert!(far.texels_per_unit < 0.41, "{far:?}");
        assert!(needs.iter().all(|n| n.weight <= 640.0));
    }

    /// One receiver at the camera asking for 1000 times what the rest ask for takes the largest
    /// map, but the others keep maps above twice the smallest (sizes in proportion to what
    /// each asks for would leave them about a twentieth of its side).
    #[test]
    fn a_receiver_at_the_camera_does_not_starve_the_others() {
        let light = Vec3::ZERO;
        let mut needs = room();
        needs.push(Need {
            bounds: cube(Vec3::new(40.0, 5.0, 5.0), 1.0),
            texels_per_unit: 1000.0,
            weight: 640.0,
        });
        let f = choose(light, &needs, &budget(256));
        let smallest = f.iter().map(|f| f.size).min().unwrap();
        let own = f
            .iter()
            .find(|f| f.face == 0 && f.cell.contains(Vec2::new(-0.125, -0.125)))
            .unwrap();
        assert!(f.iter().all(|g| g.size <= own.size), "{f:?}");
        assert!(smallest > 2 * budget(256).min_size, "{f:?}");
    }

    /// A face's cells never overlap and each frustum's rectangle lies in its cell: a fragment
    /// has one frustum, and that frustum's map holds it.
    #[test]
    fn cells_partition_and_hold_their_rectangles() {
        let mut rng = fastrand::Rng::with_seed(11);
        for _ in 0..100 {
            let needs: Vec<Need> = (0..rng.usize(1..30))
                .map(|_| {
                    let c = (Vec3::new(rng.f32(), rng.f32(), rng.f32()) - 0.5) * 300.0;
                    Need {
                        bounds: cube(c, 1.0 + rng.f32() * 20.0),
                        texels_per_unit: 0.1 + rng.f32().powi(3) * 20.0,
                        weight: 1.0 + rng.f32() * 300.0,
                    }
                })
                .collect();
            let f = choose(Vec3::ZERO, &needs, &budget(256));
            for (i, a) in f.iter().enumerate() {
                assert!(
                    a.rect.min.cmpge(a.cell.min).all() && a.rect.max.cmple(a.cell.max).all(),
                    "{a:?}"
                );
                for c in &f[i + 1..] {
                    assert!(a.face != c.face || !a.cell.overlaps(&c.cell), "{a:?} {c:?}");
                }
            }
        }
    }

    /// Frusta stay valid while the receivers stay within them: a receiver moved inside its
    /// rectangle keeps them, one moved out of it (or onto a face without frusta) does not.
    #[test]
    fn kept_frusta_serve_while_the_receivers_stay_within_them() {
        let light = Vec3::ZERO;
        let need = |c: Vec3| Need {
            bounds: cube(c, 5.0),
            texels_per_unit: 2.0,
            weight: 20.0,
        };
        let big = Need {
            bounds: cube(Vec3::new(100.0, 0.0, 0.0), 40.0),
            texels_per_unit: 1.0,
            weight: 100.0,
        };
        let kept = choose(
            light,
            &[big, need(Vec3::new(100.0, 10.0, 0.0))],
            &budget(256),
        );
        assert!(still_cover(
            light,
            &kept,
            &[big, need(Vec3::new(100.0, 12.0, 0.0))],
            1e-4
        ));
        assert!(!still_cover(
            light,
            &kept,
            &[big, need(Vec3::new(100.0, 90.0, 0.0))],
            1e-4
        ));
        assert!(!still_cover(
            light,
            &kept,
            &[big, need(Vec3::new(-100.0, 0.0, 0.0))],
            1e-4
        ));
    }

    #[test]
    fn the_projection_maps_the_rectangle_to_the_map_within_its_margin() {
        let f = FaceFrustum {
            face: 2,
            rect: Rect {
                min: Vec2::new(-0.5, 0.1),
                max: Vec2::new(0.25, 0.9),
            },
            cell: Rect::FACE,
            size: 64,
        };
        let (near, far) = (2.0, 300.0);
        let m = f.projection(near, far);
        // The rectangle ends MARGIN_TEXELS texels inside the map's edges.
        let inner = 1.0 - 2.0 * MARGIN_TEXELS as f32 / 64.0;
        for (corner, want) in [
            (Vec2::new(-0.5, 0.1), Vec2::splat(-inner)),
            (Vec2::new(0.25, 0.9), Vec2::splat(inner)),
        ] {
            let eye = (corner * 50.0).extend(-50.0);
            let clip = m.project_point3(eye);
            assert!(
                (clip.truncate() - want).abs().max_element() < 1e-5,
                "{clip:?}"
            );
        }
    }
}
