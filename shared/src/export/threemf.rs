//! 3MF (3D Manufacturing Format, core specification with base materials): one mesh object per
//! material, each pointing at its base material, in millimetres, so a multi-material slicer assigns
//! one extruder or print head per material. The package is an OPC zip with stored (uncompressed)
//! parts, which the format allows and keeps the dependency small.

use std::fmt::Write as _;
use std::io::{Cursor, Write};

use super::material_meshes_mm;
use super::mesh::TriangleMesh;
use crate::material::Palette;
use crate::voxel::VoxelGrid;

const CONTENT_TYPES: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types"><Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/><Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/></Types>
"#;

const RELATIONSHIPS: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships"><Relationship Target="/3D/3dmodel.model" Id="rel0" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/></Relationships>
"#;

/// The model part: base materials (id 1, one per palette entry) and one object per non-empty
/// mesh of `meshes` (millimetres, index = material id).
fn model_xml(meshes: &[TriangleMesh], palette: &Palette) -> String {
    let mut x = String::new();
    let _ = writeln!(x, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        x,
        r#"<model unit="millimeter" xml:lang="en-US" xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02"><resources>"#
    );
    let _ = write!(x, r#"<basematerials id="1">"#);
    for (_, m) in palette.iter() {
        let [r, g, b] = m.colour;
        let _ = write!(
            x,
            r##"<base name="{}" displaycolor="#{r:02X}{g:02X}{b:02X}FF"/>"##,
            super::xml_escape(&m.name)
        );
    }
    let _ = writeln!(x, "</basematerials>");
    let mut objects = Vec::new();
    for (m, mesh) in meshes.iter().enumerate() {
        if mesh.triangles.is_empty() {
            continue;
        }
        let id = m + 2;
        objects.push(id);
        // Named after its material, so a slicer's object list says which body is which.
        let _ = write!(
            x,
            r#"<object id="{id}" name="{}" type="model" pid="1" pindex="{m}"><mesh><vertices>"#,
            super::xml_escape(palette.0.get(m).map_or("", |p| &p.name))
        );
        for v in &mesh.vertices {
            let _ = write!(x, r#"<vertex x="{}" y="{}" z="{}"/>"#, v[0], v[1], v[2]);
        }
        let _ = write!(x, "</vertices><triangles>");
        for t in &mesh.triangles {
            let _ = write!(
                x,
                r#"<triangle v1="{}" v2="{}" v3="{}"/>"#,
                t[0], t[1], t[2]
            );
        }
        let _ = writeln!(x, "</triangles></mesh></object>");
    }
    let _ = write!(x, "</resources><build>");
    for id in objects {
        let _ = write!(x, r#"<item objectid="{id}"/>"#);
    }
    let _ = writeln!(x, "</build></model>");
    x
}

/// The whole .3mf package of a design as bytes.
pub fn write_3mf(
    grid: &VoxelGrid,
    palette: &Palette,
    voxel_size: f64,
) -> zip::result::ZipResult<Vec<u8>> {
    package_3mf(
        &material_meshes_mm(grid, palette.len(), voxel_size),
        palette,
    )
}

/// The .3mf package of per-material meshes already built (millimetres, index = material id).
pub fn package_3mf(meshes: &[TriangleMesh], palette: &Palette) -> zip::result::ZipResult<Vec<u8>> {
    let mut zip = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let options =
        zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    for (name, content) in [
        ("[Content_Types].xml", CONTENT_TYPES.to_string()),
        ("_rels/.rels", RELATIONSHIPS.to_string()),
        ("3D/3dmodel.model", model_xml(meshes, palette)),
    ] {
        zip.start_file(name, options)?;
        zip.write_all(content.as_bytes())?;
    }
    Ok(zip.finish()?.into_inner())
}
