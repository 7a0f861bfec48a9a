//! VTK XML PolyData whose arrays follow the XML as raw little-endian binary (`<AppendedData
//! encoding="raw">`, 64-bit block headers): a third of the size of ASCII and read by
//! ParaView and VTK's `vtkXMLPolyDataReader` as it is.

use glam::DVec3;
use std::fmt::Write as _;

/// A value type of a data array, with its VTK name.
pub trait VtkValue: bytemuck::Pod {
    /// The VTK type name (`Float64`, ...).
    const NAME: &'static str;
}

impl VtkValue for f64 {
    const NAME: &'static str = "Float64";
}

impl VtkValue for i64 {
    const NAME: &'static str = "Int64";
}

impl VtkValue for u8 {
    const NAME: &'static str = "UInt8";
}

/// A PolyData document being written: the XML so far and the appended bytes.
pub struct AppendedVtp {
    xml: String,
    data: Vec<u8>,
}

impl AppendedVtp {
    /// A piece of `points` points, `verts` vertices and `lines` lines; the sections and
    /// their arrays follow ([`Self::open`], [`Self::array`], [`Self::close`]).
    pub fn new(points: usize, verts: usize, lines: usize) -> Self {
        let mut xml = String::from("<?xml version=\"1.0\"?>\n");
        xml.push_str(r#"<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">"#);
        xml.push_str("\n  <PolyData>\n");
        let _ = writeln!(
            xml,
            r#"    <Piece NumberOfPoints="{points}" NumberOfVerts="{verts}" NumberOfLines="{lines}" NumberOfStrips="0" NumberOfPolys="0">"#
        );
        Self {
            xml,
            data: Vec::new(),
        }
    }

    /// Opens a section (`Points`, `PointData`, `CellData`, `Verts`, `Lines`) with its
    /// attributes (`Scalars="..."`, or empty).
    pub fn open(&mut self, section: &str, attributes: &str) {
        let _ = writeln!(self.xml, "      <{section}{attributes}>");
    }

    /// Closes a section.
    pub fn close(&mut self, section: &str) {
        let _ = writeln!(self.xml, "      </{section}>");
    }

    /// An array `name` of `components` values per tuple.
    pub fn array<T: VtkValue>(&mut self, name: &str, components: usize, values: &[T]) {
        let _ = writeln!(
            self.xml,
            r#"        <DataArray type="{}" Name="{name}" NumberOfComponents="{components}" format="appended" offset="{}"/>"#,
            T::NAME,
            self.data.len()
        );
        let bytes: &[u8] = bytemuck::cast_slice(values);
        self.data
            .extend_from_slice(&(bytes.len() as u64).to_le_bytes());
        self.data.extend_from_slice(bytes);
    }

    /// An array of 3-vectors.
    pub fn vectors(&mut self, name: &str, values: &[DVec3]) {
        let flat: Vec<f64> = values.iter().flat_map(|v| v.to_array()).collect();
        self.array(name, 3, &flat);
    }

    /// The document's bytes.
    pub fn finish(self) -> Vec<u8> {
        let mut out = self.xml.into_bytes();
        out.extend_from_slice(b"    </Piece>\n  </PolyData>\n  <AppendedData encoding=\"raw\">\n_");
        out.extend_from_slice(&self.data);
        out.extend_from_slice(b"\n  </AppendedData>\n</VTKFile>\n");
        out
    }
}

/// Reads array `name` of a document [`AppendedVtp`] wrote, as f64 (for tests and tools);
/// `None` where it is not there.
pub fn read_array(doc: &[u8], name: &str) -> Option<Vec<f64>> {
    let marker = doc.windows(2).position(|w| w == b"\n_")? + 2;
    let xml = std::str::from_utf8(&doc[..marker]).ok()?;
    let tag = xml
        .lines()
        .find(|l| l.contains(&format!(r#"Name="{name}""#)))?;
    let attr = |a: &str| tag.split(&format!(r#"{a}=""#)).nth(1)?.split('"').next();
    let offset: usize = attr("offset")?.parse().ok()?;
    let block = doc.get(marker + offset..)?;
    let len = u64::from_le_bytes(block.get(..8)?.try_into().ok()?) as usize;
    let bytes = block.get(8..8 + len)?;
    Some(match attr("type")? {
        "Float64" => bytes
            .chunks_exact(8)
            .map(|b| f64::from_le_bytes(b.try_into().unwrap_or_default()))
            .collect(),
        "Int64" => bytes
            .chunks_exact(8)
            .map(|b| i64::from_le_bytes(b.try_into().unwrap_or_default()) as f64)
            .collect(),
        "UInt8" => bytes.iter().map(|&b| b as f64).collect(),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrays_read_back_from_their_offsets() {
        let mut d = AppendedVtp::new(2, 0, 1);
        d.open("Points", "");
        d.vectors("position", &[DVec3::new(1.0, 2.0, 3.0), DVec3::splat(-0.5)]);
        d.close("Points");
        d.open("CellData", "");
        d.array("flag", 1, &[1u8]);
        d.array("id", 1, &[-7i64]);
        d.close("CellData");
        let doc = d.finish();
        let text = String::from_utf8_lossy(&doc);
        assert!(text.contains(r#"header_type="UInt64""#) && text.ends_with("</VTKFile>\n"));
        assert_eq!(
            read_array(&doc, "position"),
            Some(vec![1.0, 2.0, 3.0, -0.5, -0.5, -0.5])
        );
        assert_eq!(read_array(&doc, "flag"), Some(vec![1.0]));
        assert_eq!(read_array(&doc, "id"), Some(vec![-7.0]));
        assert_eq!(read_array(&doc, "missing"), None);
    }
}
