//! File formats, told by the file name's extension (case-insensitive), in one place.

use std::path::Path;

/// Every file format the library reads or writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileFormat {
    /// Wavefront OBJ (with MTL materials): scenes in.
    Obj,
    /// Materials and Geometry Format (RenderPark's scenes): scenes in.
    Mgf,
    /// glTF 2.0, JSON: scenes in, baked meshes out.
    Gltf,
    /// glTF 2.0, binary: scenes in, baked meshes out.
    Glb,
    /// Polygon File Format: scenes in, baked meshes out.
    Ply,
    /// 8-bit sRGB PNG: images out.
    Png,
    /// OpenEXR: linear images out.
    Exr,
    /// Portable float map: linear images out.
    Pfm,
    /// Comma-separated values: patch tables, radiosities, traces.
    Csv,
    /// Matrix Market: form-factor matrices.
    MatrixMarket,
    /// NIST View3D input: view-factor geometry in.
    Vs3,
}

impl FileFormat {
    /// The format `path`'s extension names, if any.
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "obj" => Self::Obj,
            "mgf" => Self::Mgf,
            "gltf" => Self::Gltf,
            "glb" => Self::Glb,
            "ply" => Self::Ply,
            "png" => Self::Png,
            "exr" => Self::Exr,
            "pfm" => Self::Pfm,
            "csv" => Self::Csv,
            "mtx" => Self::MatrixMarket,
            "vs3" => Self::Vs3,
            _ => return None,
        })
    }

    /// True for the formats a baked mesh can be written to.
    pub fn is_baked_mesh(self) -> bool {
        matches!(self, Self::Gltf | Self::Glb | Self::Ply)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extensions_are_case_insensitive() {
        assert_eq!(
            FileFormat::from_path(Path::new("a/B.GLB")),
            Some(FileFormat::Glb)
        );
        assert_eq!(
            FileFormat::from_path(Path::new("x.mtx")),
            Some(FileFormat::MatrixMarket)
        );
        assert_eq!(FileFormat::from_path(Path::new("noext")), None);
        assert_eq!(FileFormat::from_path(Path::new("x.txt")), None);
        assert!(FileFormat::Ply.is_baked_mesh() && !FileFormat::Obj.is_baked_mesh());
    }
}
