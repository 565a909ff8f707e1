//! Self-collision between non-adjacent surface voxels, found with a spatial hash rebuilt every step
//! (counting sort into preallocated buckets: no allocation, no all-pairs scan). Voxels collide as
//! spheres of diameter s with a penalty force of the softer voxel's stiffness E·s.

use super::math::Vec3;
use super::state::Voxels;

/// Preallocated spatial hash over the surface voxels.
#[derive(Clone, Debug, Default)]
pub struct Collisions {
    /// Indices of surface voxels (fewer than six face neighbours).
    surface: Vec<u32>,
    /// Hash cell of each surface voxel this step.
    cell_of: Vec<[i64; 3]>,
    /// Bucket start offsets (len buckets + 1) and the surface slots sorted by bucket.
    start: Vec<u32>,
    sorted: Vec<u32>,
    mask: usize,
}

fn bucket(cell: [i64; 3], mask: usize) -> usize {
    // Three large odd primes (Teschner et al. 2003 style spatial hashing).
    let h = (cell[0].wrapping_mul(73_856_093))
        ^ (cell[1].wrapping_mul(19_349_663))
        ^ (cell[2].wrapping_mul(83_492_791));
    (h as u64 as usize) & mask
}

impl Collisions {
    pub fn new(voxels: &Voxels, _voxel_size: f64) -> Self {
        let mut occupied = std::collections::HashSet::new();
        for c in &voxels.cell {
            occupied.insert(*c);
        }
        let neighbours = |c: [u16; 3]| {
            let mut count = 0;
            for (axis, delta) in [(0, -1i32), (0, 1), (1, -1), (1, 1), (2, -1), (2, 1)] {
                let mut n = [i32::from(c[0]), i32::from(c[1]), i32::from(c[2])];
                n[axis] += delta;
                if n.iter().all(|&x| (0..=i32::from(u16::MAX)).contains(&x))
                    && occupied.contains(&[n[0] as u16, n[1] as u16, n[2] as u16])
                {
                    count += 1;
                }
            }
            count
        };
        let surface: Vec<u32> = (0..voxels.len())
            .filter(|&i| neighbours(voxels.cell[i]) < 6)
            .map(|i| i as u32)
            .collect();
        let buckets = (2 * surface.len()).next_power_of_two().max(16);
        Self {
            cell_of: vec![[0; 3]; surface.len()],
            start: vec![0; buckets + 1],
            sorted: vec![0; surface.len()],
            surface,
            mask: buckets - 1,
        }
    }

    /// Adds penalty forces between overlapping non-adjacent surface voxels.
    #[inline(never)]
    pub fn pass(&mut self, voxels: &mut Voxels, voxel_size: f64) {
        let s = voxel_size;
        let inv_s = 1.0 / s;
        let mask = self.mask;
        self.start.iter_mut().for_each(|c| *c = 0);
        for (slot, &i) in self.surface.iter().enumerate() {
            let p = voxels.position[i as usize];
            let cell = [
                (p.x * inv_s).floor() as i64,
                (p.y * inv_s).floor() as i64,
                (p.z * inv_s).floor() as i64,
            ];
            self.cell_of[slot] = cell;
            self.start[bucket(cell, mask) + 1] += 1;
        }
        for b in 0..=mask {
            self.start[b + 1] += self.start[b];
        }
        // Fill from the back so each bucket keeps slot order (deterministic).
        for slot in (0..self.surface.len()).rev() {
            let b = bucket(self.cell_of[slot], mask);
            self.start[b + 1] -= 1;
            self.sorted[self.start[b + 1] as usize] = slot as u32;
        }
        // The fill moved each bucket's end down to its beginning, now held one slot late: shift
        // back so bucket b spans start[b]..start[b + 1].
        for b in 0..=mask {
            self.start[b] = self.start[b + 1];
        }
        self.start[mask + 1] = self.surface.len() as u32;
        for slot_a in 0..self.surface.len() {
            let ia = self.surface[slot_a] as usize;
            let ca = self.cell_of[slot_a];
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let probe = [ca[0] + dx, ca[1] + dy, ca[2] + dz];
                        let b = bucket(probe, mask);
                        for k in self.start[b] as usize..self.start[b + 1] as usize {
                            let slot_b = self.sorted[k] as usize;
                            if slot_b <= slot_a || self.cell_of[slot_b] != probe {
                                continue;
                            }
                            let ib = self.surface[slot_b] as usize;
                            collide_pair(voxels, ia, ib, s);
                        }
                    }
                }
            }
        }
    }
}

#[inline(always)]
fn collide_pair(voxels: &mut Voxels, ia: usize, ib: usize, s: f64) {
    let (ca, cb) = (voxels.cell[ia], voxels.cell[ib]);
    let manhattan: u32 = (0..3).map(|k| u32::from(ca[k].abs_diff(cb[k]))).sum();
    if manhattan <= 1 {
        return; // linked neighbours: the link handles them
    }
    let r = voxels.position[ib] - voxels.position[ia];
    let dist2 = r.norm2();
    if dist2 >= s * s || dist2 == 0.0 {
        return;
    }
    let dist = dist2.sqrt();
    let k = voxels.stiffness[ia].min(voxels.stiffness[ib]);
    let push: Vec3 = r * (k * (s - dist) / dist);
    voxels.force[ib] += push;
    voxels.force[ia] -= push;
}
