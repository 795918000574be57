//! BSP visibility of a Quake 3 world (paper 2.2): the camera's leaf and cluster, the potentially visible set, and
//! frustum culling of node and leaf boxes. Each surface is drawn once however many leaves hold it.

use crate::geometry::Aabb;
use crate::geometry::Frustum;
use glam::Vec3;
use serde::Serialize;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    pub normal: [f32; 3],
    pub dist: f32,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Node {
    pub plane: u32,
    /// ≥ 0: a node; < 0: leaf `-(child + 1)`.
    pub children: [i32; 2],
    pub mins: [i32; 3],
    pub maxs: [i32; 3],
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Leaf {
    /// -1: outside the map (solid or void).
    pub cluster: i32,
    pub area: i32,
    pub mins: [i32; 3],
    pub maxs: [i32; 3],
    pub first_leaf_surface: u32,
    pub num_leaf_surfaces: u32,
    pub first_leaf_brush: u32,
    pub num_leaf_brushes: u32,
}

/// The potentially visible set: one bit row per cluster.
#[derive(Debug, Clone, PartialEq)]
pub struct Vis {
    pub num_clusters: u32,
    pub cluster_bytes: u32,
    pub data: Vec<u8>,
}

impl Vis {
    /// Whether `to` may be seen from `from`. Clusters outside the table (e.g. -1) see nothing.
    pub fn visible(&self, from: i32, to: i32) -> bool {
        if from < 0 || to < 0 || from as u32 >= self.num_clusters || to as u32 >= self.num_clusters
        {
            return false;
        }
        let row = from as usize * self.cluster_bytes as usize;
        self.data[row + (to as usize >> 3)] & (1 << (to & 7)) != 0
    }
}

/// What a map's loader hands to [`WorldVis::new`]: the BSP tree and the PVS.
#[derive(Debug, Clone, PartialEq)]
pub struct BspTree {
    pub planes: Vec<Plane>,
    pub nodes: Vec<Node>,
    pub leafs: Vec<Leaf>,
    pub leaf_surfaces: Vec<u32>,
    pub vis: Option<Vis>,
}

/// The parts of a map that visibility needs, with BSP surfaces mapped to scene surfaces.
#[derive(Debug, Clone)]
pub struct WorldVis {
    planes: Vec<Plane>,
    nodes: Vec<Node>,
    leafs: Vec<Leaf>,
    leaf_surfaces: Vec<u32>,
    vis: Option<Vis>,
    /// BSP surface → scene surface (None: not drawn, e.g. a flare or another model's surface).
    surface_map: Vec<Option<u32>>,
}

/// What visibility culled this frame (for stats overlays and bench JSON).
#[derive(Debug, Clone, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct VisStats {
    pub camera_leaf: Option<usize>,
    pub camera_cluster: i32,
    pub leaves: usize,
    pub leaves_outside_pvs: usize,
    pub leaves_outside_frustum: usize,
    pub nodes_outside_frustum: usize,
    pub surfaces_marked: usize,
}

fn ibox(mins: [i32; 3], maxs: [i32; 3]) -> Aabb {
    Aabb {
        min: Vec3::new(mins[0] as f32, mins[1] as f32, mins[2] as f32),
        max: Vec3::new(maxs[0] as f32, maxs[1] as f32, maxs[2] as f32),
    }
}

impl WorldVis {
    /// The map's BSP tree, leaves and PVS, with `surface_map` taking BSP surfaces to scene
    /// surfaces.
    pub fn new(tree: BspTree, surface_map: Vec<Option<u32>>) -> WorldVis {
        let BspTree {
            planes,
            nodes,
            leafs,
            leaf_surfaces,
            vis,
        } = tree;
        WorldVis {
            planes,
            nodes,
            leafs,
            leaf_surfaces,
            vis,
            surface_map,
        }
    }

    pub fn leaf_count(&self) -> usize {
        self.leafs.len()
    }

    pub fn cluster_count(&self) -> usize {
        self.vis.as_ref().map_or(0, |v| v.num_clusters as usize)
    }

    /// The leaf holding `p` (finite: node children always come after their parent).
    pub fn leaf_at(&self, p: Vec3) -> Option<usize> {
        if self.nodes.is_empty() {
            return (!self.leafs.is_empty()).then_some(0);
        }
        let mut node = 0usize;
        loop {
            let n = &self.nodes[node];
            let pl = &self.planes[n.plane as usize];
            let d = Vec3::from_array(pl.normal).dot(p) - pl.dist;
            let child = n.children[if d >= 0.0 { 0 } else { 1 }];
            if child < 0 {
                return Some((-(child + 1)) as usize);
            }
            node = child as usize;
        }
    }

    /// The cluster holding `p`, -1 outside the map.
    pub fn cluster_at(&self, p: Vec3) -> i32 {
        self.leaf_at(p).map_or(-1, |l| self.leafs[l].cluster)
    }

    /// Whether cluster `to` may be seen from `from`. Without vis data, or from outside the map,
    /// everything may be seen (Quake 3 does the same).
    pub fn cluster_visible(&self, from: i32, to: i32) -> bool {
        match &self.vis {
            Some(v) if from >= 0 => v.visible(from, to),
            _ => true,
        }
    }

    /// Marks in `visible` (indexed by scene surface) every surface of a leaf in the camera's PVS
    /// whose box meets the frustum. `use_pvs` / `frustum` = None switch either test off.
    pub fn mark_visible(
        &self,
        eye: Vec3,
        frustum: Option<&Frustum>,
        use_pvs: bool,
        visible: &mut [bool],
    ) -> VisStats {
        let camera_leaf = self.leaf_at(eye);
        let cluster = camera_leaf.map_or(-1, |l| self.leafs[l].cluster);
        let mut stats = VisStats {
            camera_leaf,
            camera_cluster: cluster,
            leaves: self.leafs.len(),
            ..VisStats::default()
        };
        let mut mark_leaf = |leaf: usize, stats: &mut VisStats| {
            let l = &self.leafs[leaf];
            if use_pvs && !self.cluster_visible(cluster, l.cluster) {
                stats.leaves_outside_pvs += 1;
                return;
            }
            if let Some(f) = frustum
                && !f.intersects_aabb(&ibox(l.mins, l.maxs))
            {
                stats.leaves_outside_frustum += 1;
                return;
            }
            let range = l.first_leaf_surface as usize
                ..(l.first_leaf_surface + l.num_leaf_surfaces) as usize;
            for &s in &self.leaf_surfaces[range] {
                if let Some(Some(scene_surface)) = self.surface_map.get(s as usize)
                    && let Some(slot) = visible.get_mut(*scene_surface as usize)
                    && !*slot
                {
                    *slot = true;
                    stats.surfaces_marked += 1;
                }
            }
        };
        if self.nodes.is_empty() {
            for leaf in 0..self.leafs.len() {
                mark_leaf(leaf, &mut stats);
            }
            return stats;
        }
        let mut stack = vec![0i32];
        while let Some(child) = stack.pop() {
            if child < 0 {
                mark_leaf((-(child + 1)) as usize, &mut stats);
                continue;
            }
            let n = &self.nodes[child as usize];
            if let Some(f) = frustum
                && !f.intersects_aabb(&ibox(n.mins, n.maxs))
            {
                stats.nodes_outside_frustum += 1;
                continue;
            }
            stack.extend_from_slice(&n.children);
        }
        stats
    }
}
