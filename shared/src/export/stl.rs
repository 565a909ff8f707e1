//! Binary STL: one solid per material, millimetres, all in the grid's frame so the files stack.

use std::io::{self, Read, Write};

use super::mesh::TriangleMesh;

/// Writes `mesh` (already in millimetres) as binary STL: an 80-byte header, the triangle count,
/// then per triangle its unit normal, three vertices (f32, little endian) and a zero attribute.
pub fn write_binary_stl(mesh: &TriangleMesh, header: &str, out: &mut impl Write) -> io::Result<()> {
    let mut head = [b' '; 80];
    let text = header.as_bytes();
    head[..text.len().min(80)].copy_from_slice(&text[..text.len().min(80)]);
    // A header starting with "solid" makes some readers take the file for ASCII STL.
    if head.starts_with(b"solid") {
        head[..5].copy_from_slice(b"SOLID");
    }
    out.write_all(&head)?;
    let count = u32::try_from(mesh.triangles.len())
        .map_err(|_| io::Error::other("more than 2^32 triangles"))?;
    out.write_all(&count.to_le_bytes())?;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        let n = if len > 0.0 { n.map(|c| c / len) } else { n };
        for value in n.iter().chain(&a).chain(&b).chain(&c) {
            out.write_all(&(*value as f32).to_le_bytes())?;
        }
        out.write_all(&[0, 0])?;
    }
    Ok(())
}

/// Reads a binary STL back as a triangle soup: per triangle its three vertices.
pub fn read_binary_stl(input: &mut impl Read) -> io::Result<Vec<[[f32; 3]; 3]>> {
    let mut head = [0u8; 84];
    input.read_exact(&mut head)?;
    let count = u32::from_le_bytes([head[80], head[81], head[82], head[83]]) as usize;
    let mut triangles = Vec::with_capacity(count.min(1 << 24));
    let mut record = [0u8; 50];
    for _ in 0..count {
        input.read_exact(&mut record)?;
        let f = |i: usize| {
            let o = 12 + 4 * i;
            f32::from_le_bytes([record[o], record[o + 1], record[o + 2], record[o + 3]])
        };
        triangles.push([[f(0), f(1), f(2)], [f(3), f(4), f(5)], [f(6), f(7), f(8)]]);
    }
    let mut rest = [0u8; 1];
    if input.read(&mut rest)? != 0 {
        return Err(io::Error::other("bytes after the last triangle"));
    }
    Ok(triangles)
}
