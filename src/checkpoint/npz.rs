//! A NumPy `.npz` archive (a zip of `.npy` arrays, stored uncompressed), written and read
//! without a dependency: named little-endian arrays with their dtype and shape, plus raw
//! members such as a JSON header. `numpy.load` reads it as it is; each member carries the
//! zip CRC-32 of its bytes, checked on reading. ZIP64 records are written where a member or
//! offset passes 4 GiB (large GPU states).

use std::collections::BTreeMap;

/// One `.npy` array: its dtype (`descr`, e.g. `<f8` or a structured list), shape and bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct Array {
    /// The NumPy dtype description, as `.npy` headers write it.
    pub descr: String,
    /// The shape (empty: a scalar).
    pub shape: Vec<usize>,
    /// The values, C order, little-endian.
    pub data: Vec<u8>,
}

impl Array {
    /// `values` as a 1-d array of `descr` (`<f8`, `<u8`, `|b1`, `|u1`, ...).
    pub fn of<T: bytemuck::Pod>(descr: &str, values: &[T]) -> Self {
        Self {
            descr: descr.into(),
            shape: vec![values.len()],
            data: bytemuck::cast_slice(values).to_vec(),
        }
    }

    /// One f64 as a 0-d array.
    pub fn scalar_f64(v: f64) -> Self {
        Self {
            descr: "<f8".into(),
            shape: Vec::new(),
            data: v.to_le_bytes().to_vec(),
        }
    }

    /// One u64 as a 0-d array.
    pub fn scalar_u64(v: u64) -> Self {
        Self {
            descr: "<u8".into(),
            shape: Vec::new(),
            data: v.to_le_bytes().to_vec(),
        }
    }

    /// The `.npy` file: magic, version 1.0, the header dict padded to 64 bytes, the data.
    fn npy(&self) -> Vec<u8> {
        let shape = match self.shape.as_slice() {
            [] => "()".to_string(),
            [n] => format!("({n},)"),
            dims => format!(
                "({})",
                dims.iter()
                    .map(|d| d.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        let descr = if self.descr.starts_with('[') {
            self.descr.clone()
        } else {
            format!("'{}'", self.descr)
        };
        let mut header =
            format!("{{'descr': {descr}, 'fortran_order': False, 'shape': {shape}, }}");
        // magic (6) + version (2) + length (2) + header + '\n', a multiple of 64
        let used = 10 + header.len() + 1;
        header.push_str(&" ".repeat((64 - used % 64) % 64));
        header.push('\n');
        let mut out = b"\x93NUMPY\x01\x00".to_vec();
        out.extend((header.len() as u16).to_le_bytes());
        out.extend(header.as_bytes());
        out.extend(&self.data);
        out
    }

    /// Parses a `.npy` file of version 1.0 (what [`Self::npy`] writes).
    fn parse(bytes: &[u8]) -> Option<Self> {
        if !bytes.starts_with(b"\x93NUMPY\x01\x00") {
            return None;
        }
        let len = u16::from_le_bytes(bytes.get(8..10)?.try_into().ok()?) as usize;
        let header = std::str::from_utf8(bytes.get(10..10 + len)?).ok()?;
        let descr = header.strip_prefix("{'descr': ")?;
        let end = descr.find(", 'fortran_order': False, 'shape': (")?;
        let (descr, rest) = descr.split_at(end);
        let descr = descr.trim_matches('\'').to_string();
        let shape = rest.split("'shape': (").nth(1)?.split(')').next()?;
        let shape = shape
            .split(',')
            .map(str::trim)
            .filter(|d| !d.is_empty())
            .map(|d| d.parse().ok())
            .collect::<Option<Vec<usize>>>()?;
        Some(Self {
            descr,
            shape,
            data: bytes[10 + len..].to_vec(),
        })
    }
}

/// What one member of the archive holds.
#[derive(Clone, Debug, PartialEq)]
pub enum Member {
    /// A `.npy` array (the member's name gets `.npy` appended).
    Array(Array),
    /// Raw bytes (a JSON header, say), under the name as given.
    Raw(Vec<u8>),
}

/// Why an archive could not be read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum NpzError {
    /// Not a zip archive, or cut short (its directory is missing or points past the end).
    NotAnArchive,
    /// A member's bytes do not match their CRC-32.
    Damaged(String),
    /// A member that is not a `.npy` array of the version written here.
    NotAnArray(String),
}

/// The archive of `members`, in order: `(name, member)`.
pub fn write(members: &[(String, Member)]) -> Vec<u8> {
    write_with(members, 0xFFFF_FFFF)
}

/// [`write`] with ZIP64 records for every size or offset from `limit` on (4 GiB − 1; the
/// tests force them with 0).
fn write_with(members: &[(String, Member)], limit: u64) -> Vec<u8> {
    let items: Vec<(String, Vec<u8>)> = members
        .iter()
        .map(|(name, member)| match member {
            Member::Array(a) => (format!("{name}.npy"), a.npy()),
            Member::Raw(b) => (name.clone(), b.clone()),
        })
        .collect();
    let entries: Vec<(&str, u64, u32)> = (items.iter())
        .map(|(name, bytes)| (name.as_str(), bytes.len() as u64, crc32fast::hash(bytes)))
        .collect();
    let (locals, tail) = frame(&entries, limit);
    let mut out = Vec::new();
    for (local, (_, bytes)) in locals.iter().zip(&items) {
        out.extend(local);
        out.extend(bytes);
    }
    out.extend(tail);
    out
}

/// The bytes [`write_with`] puts around the members' data, for members (name, size, CRC)
/// in order: each one's local header (its data follow it), then the central directory and
/// the end records.
fn frame(entries: &[(&str, u64, u32)], limit: u64) -> (Vec<Vec<u8>>, Vec<u8>) {
    let mut locals = Vec::new();
    let mut central = Vec::new();
    let mut offset = 0u64;
    for &(name, size, crc) in entries {
        let zip64 = size >= limit || offset >= limit;
        let mut local = Vec::new();
        // local header: sizes in a ZIP64 extra field where they do not fit
        local.extend(0x0403_4b50u32.to_le_bytes());
        local.extend(if zip64 { 45u16 } else { 20u16 }.to_le_bytes());
        local.extend([0u8; 2]); // flags
        local.extend([0u8; 2]); // stored
        local.extend([0u8, 0, 0x21, 0]); // 1980-01-01 00:00: no time, for reproducible bytes
        local.extend(crc.to_le_bytes());
        let small = |v: u64| if zip64 { 0xFFFF_FFFFu32 } else { v as u32 };
        local.extend(small(size).to_le_bytes());
        local.extend(small(size).to_le_bytes());
        local.extend((name.len() as u16).to_le_bytes());
        local.extend(if zip64 { 20u16 } else { 0u16 }.to_le_bytes());
        local.extend(name.as_bytes());
        if zip64 {
            local.extend(1u16.to_le_bytes());
            local.extend(16u16.to_le_bytes());
            local.extend(size.to_le_bytes());
            local.extend(size.to_le_bytes());
        }
        // its central directory record
        central.extend(0x0201_4b50u32.to_le_bytes());
        central.extend(if zip64 { 45u16 } else { 20u16 }.to_le_bytes());
        central.extend(if zip64 { 45u16 } else { 20u16 }.to_le_bytes());
        central.extend([0u8; 4]); // flags, stored
        central.extend([0u8, 0, 0x21, 0]);
        central.extend(crc.to_le_bytes());
        central.extend(small(size).to_le_bytes());
        central.extend(small(size).to_le_bytes());
        central.extend((name.len() as u16).to_le_bytes());
        central.extend(if zip64 { 28u16 } else { 0u16 }.to_le_bytes());
        central.extend([0u8; 10]); // comment length, disk, internal and external attributes
        central.extend(small(offset).to_le_bytes());
        central.extend(name.as_bytes());
        if zip64 {
            central.extend(1u16.to_le_bytes());
            central.extend(24u16.to_le_bytes());
            central.extend(size.to_le_bytes());
            central.extend(size.to_le_bytes());
            central.extend(offset.to_le_bytes());
        }
        offset += local.len() as u64 + size;
        locals.push(local);
    }
    let count = entries.len() as u64;
    let (cd_offset, cd_size) = (offset, central.len() as u64);
    let mut out = central;
    let zip64 = cd_offset >= limit || count >= 0xFFFF;
    if zip64 {
        let record = cd_offset + cd_size;
        out.extend(0x0606_4b50u32.to_le_bytes());
        out.extend(44u64.to_le_bytes());
        out.extend(45u16.to_le_bytes());
        out.extend(45u16.to_le_bytes());
        out.extend([0u8; 8]); // this disk, the directory's disk
        out.extend(count.to_le_bytes());
        out.extend(count.to_le_bytes());
        out.extend(cd_size.to_le_bytes());
        out.extend(cd_offset.to_le_bytes());
        out.extend(0x0706_4b50u32.to_le_bytes());
        out.extend(0u32.to_le_bytes());
        out.extend(record.to_le_bytes());
        out.extend(1u32.to_le_bytes());
    }
    let small16 = |v: u64| if zip64 { 0xFFFFu16 } else { v as u16 };
    let small32 = |v: u64| if zip64 { 0xFFFF_FFFFu32 } else { v as u32 };
    out.extend(0x0605_4b50u32.to_le_bytes());
    out.extend([0u8; 4]);
    out.extend(small16(count).to_le_bytes());
    out.extend(small16(count).to_le_bytes());
    out.extend(small32(cd_size).to_le_bytes());
    out.extend(small32(cd_offset).to_le_bytes());
    out.extend(0u16.to_le_bytes());
    (locals, out)
}

/// Whether `b` holds exactly what [`write_with`] writes for `members` (name, data, CRC) in
/// order, at the default or the forced ZIP64 limit: the data are checked by their CRCs,
/// every other byte here.
fn framed_as_written(b: &[u8], members: &[(&str, &[u8], u32)]) -> bool {
    let entries: Vec<(&str, u64, u32)> = (members.iter())
        .map(|&(name, data, crc)| (name, data.len() as u64, crc))
        .collect();
    [0xFFFF_FFFF, 0].into_iter().any(|limit| {
        let (locals, tail) = frame(&entries, limit);
        let mut at = 0usize;
        for (local, (_, data, _)) in locals.iter().zip(members) {
            if b.get(at..at + local.len()) != Some(&local[..]) {
                return false;
            }
            at += local.len() + data.len();
        }
        b.get(at..) == Some(&tail[..])
    })
}

/// The `N` bytes at `at` (none past the end, or where `at + N` overflows).
fn bytes_at<const N: usize>(b: &[u8], at: usize) -> Option<[u8; N]> {
    b.get(at..at.checked_add(N)?)?.try_into().ok()
}

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    bytes_at(b, at).map(u16::from_le_bytes)
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    bytes_at(b, at).map(u32::from_le_bytes)
}

fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    bytes_at(b, at).map(u64::from_le_bytes)
}

/// The first member of the archive `r` reads, `(name, bytes)`, its CRC checked, without
/// reading further (a large archive's header member); `None` where that is not a stored
/// member of at most `limit` bytes as [`write`](fn@write) writes it.
pub fn first_member(mut r: impl std::io::Read, limit: u64) -> Option<(String, Vec<u8>)> {
    let mut local = [0u8; 30];
    r.read_exact(&mut local).ok()?;
    if u32_at(&local, 0)? != 0x0403_4b50 || u16_at(&local, 8)? != 0 {
        return None;
    }
    let crc = u32_at(&local, 14)?;
    let mut size = u32_at(&local, 22)? as u64;
    let (name_len, extra_len) = (u16_at(&local, 26)? as usize, u16_at(&local, 28)? as usize);
    let mut rest = vec![0u8; name_len + extra_len];
    r.read_exact(&mut rest).ok()?;
    let name = std::str::from_utf8(&rest[..name_len]).ok()?.to_string();
    if size == 0xFFFF_FFFF {
        // the ZIP64 extra field: (uncompressed, compressed)
        if u16_at(&rest, name_len)? != 1 {
            return None;
        }
        size = u64_at(&rest, name_len + 4)?;
    }
    if size > limit {
        return None;
    }
    let mut data = vec![0u8; usize::try_from(size).ok()?];
    r.read_exact(&mut data).ok()?;
    (crc32fast::hash(&data) == crc).then_some((name, data))
}

/// An archive read back: each member's bytes by name, CRCs checked.
pub struct Archive<'a> {
    members: BTreeMap<String, &'a [u8]>,
}

impl<'a> Archive<'a> {
    /// Reads the archive `bytes` (as [`write`](fn@write) writes it: stored members, no comment).
    pub fn read(bytes: &'a [u8]) -> Result<Self, NpzError> {
        Self::members(bytes).ok_or(NpzError::NotAnArchive)?
    }

    fn members(b: &'a [u8]) -> Option<Result<Self, NpzError>> {
        let end = b.len().checked_sub(22)?;
        // (no archive comment: the end record is the last 22 bytes)
        if u32_at(b, end)? != 0x0605_4b50 || u16_at(b, end + 20)? != 0 {
            return None;
        }
        let (mut count, mut cd_size, mut cd_offset) = (
            u16_at(b, end + 10)? as u64,
            u32_at(b, end + 12)? as u64,
            u32_at(b, end + 16)? as u64,
        );
        if count == 0xFFFF || cd_offset == 0xFFFF_FFFF {
            let locator = end.checked_sub(20)?;
            if u32_at(b, locator)? != 0x0706_4b50 {
                return None;
            }
            let record = usize::try_from(u64_at(b, locator + 8)?).ok()?;
            if record > locator {
                return None;
            }
            if u32_at(b, record)? != 0x0606_4b50 {
                return None;
            }
            count = u64_at(b, record + 32)?;
            cd_size = u64_at(b, record + 40)?;
            cd_offset = u64_at(b, record + 48)?;
        }
        let cd_start = usize::try_from(cd_offset).ok()?;
        let mut at = cd_start;
        let cd_end = at.checked_add(usize::try_from(cd_size).ok()?)?;
        if cd_end > end {
            return None;
        }
        // members one after the other, as written (so no byte is checked twice)
        let mut free = 0usize;
        let mut members = BTreeMap::new();
        let mut in_order = Vec::new();
        for _ in 0..count {
            if u32_at(b, at)? != 0x0201_4b50 || u16_at(b, at + 10)? != 0 {
                return None;
            }
            let crc = u32_at(b, at + 16)?;
            let mut size = u32_at(b, at + 24)? as u64;
            let name_len = u16_at(b, at + 28)? as usize;
            let extra_len = u16_at(b, at + 30)? as usize;
            let comment_len = u16_at(b, at + 32)? as usize;
            let mut offset = u32_at(b, at + 42)? as u64;
            let name = std::str::from_utf8(b.get(at + 46..at + 46 + name_len)?).ok()?;
            if size == 0xFFFF_FFFF || offset == 0xFFFF_FFFF {
                // the ZIP64 extra field: (uncompressed, compressed, offset) as they overflow
                let extra = at + 46 + name_len;
                if u16_at(b, extra)? != 1 {
                    return None;
                }
                let mut field = extra + 4;
                if size == 0xFFFF_FFFF {
                    size = u64_at(b, field)?;
                    field += 16;
                }
                if offset == 0xFFFF_FFFF {
                    offset = u64_at(b, field)?;
                }
            }
            let local = usize::try_from(offset).ok()?;
            if local < free || local >= cd_start || u32_at(b, local)? != 0x0403_4b50 {
                return None;
            }
            let start =
                local + 30 + u16_at(b, local + 26)? as usize + u16_at(b, local + 28)? as usize;
            let data_end = start.checked_add(usize::try_from(size).ok()?)?;
            if data_end > cd_start {
                return None;
            }
            let data = b.get(start..data_end)?;
            free = data_end;
            if crc32fast::hash(data) != crc {
                return Some(Err(NpzError::Damaged(name.to_string())));
            }
            members.insert(name.to_string(), data);
            in_order.push((name, data, crc));
            at += 46 + name_len + extra_len + comment_len;
        }
        // (a directory field the reading above does not use is checked here)
        framed_as_written(b, &in_order).then_some(Ok(Self { members }))
    }

    /// The raw member `name`.
    pub fn raw(&self, name: &str) -> Option<&'a [u8]> {
        self.members.get(name).copied()
    }

    /// The array `name` (member `name.npy`).
    pub fn array(&self, name: &str) -> Result<Option<Array>, NpzError> {
        match self.members.get(&format!("{name}.npy")) {
            None => Ok(None),
            Some(b) => Array::parse(b)
                .map(Some)
                .ok_or_else(|| NpzError::NotAnArray(name.to_string())),
        }
    }

    /// The names of the members, sorted.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.members.keys().map(String::as_str)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<(String, Member)> {
        vec![
            ("header.json".into(), Member::Raw(b"{\"a\": 1}".to_vec())),
            ("x".into(), Member::Array(Array::of("<f8", &[1.5f64, -2.0]))),
            ("t".into(), Member::Array(Array::scalar_f64(0.25))),
            (
                "v".into(),
                Member::Array(Array {
                    descr: "<f8".into(),
                    shape: vec![1, 3],
                    data: bytemuck::cast_slice(&[1.0f64, 2.0, 3.0]).to_vec(),
                }),
            ),
            (
                "rows".into(),
                Member::Array(Array {
                    descr: "[('i', '<u4'), ('f', '|b1')]".into(),
                    shape: vec![2],
                    data: vec![1, 0, 0, 0, 1, 2, 0, 0, 0, 0],
                }),
            ),
        ]
    }

    #[test]
    fn members_read_back_as_written() {
        let bytes = write(&sample());
        assert!(bytes.starts_with(b"PK\x03\x04"));
        let a = Archive::read(&bytes).unwrap();
        assert_eq!(a.raw("header.json"), Some(&b"{\"a\": 1}"[..]));
        for (name, member) in sample().into_iter().skip(1) {
            let Member::Array(want) = member else {
                unreachable!()
            };
            assert_eq!(a.array(&name).unwrap(), Some(want), "{name}");
        }
        assert_eq!(a.array("missing").unwrap(), None);
        // every .npy header is padded to a multiple of 64 bytes
        let npy = a.raw("x.npy").unwrap();
        let len = u16::from_le_bytes([npy[8], npy[9]]) as usize;
        assert_eq!((10 + len) % 64, 0);
    }

    #[test]
    fn zip64_records_read_back() {
        let bytes = write_with(&sample(), 0);
        let a = Archive::read(&bytes).unwrap();
        assert_eq!(a.names().count(), sample().len());
        assert_eq!(
            a.array("x").unwrap(),
            Some(Array::of("<f8", &[1.5f64, -2.0]))
        );
        // the end of central directory points to the ZIP64 one
        assert_eq!(u32_at(&bytes, bytes.len() - 22 - 20), Some(0x0706_4b50));
    }

    /// The first member reads alone, plain or ZIP64, and only whole, of its CRC and within
    /// the limit.
    #[test]
    fn the_first_member_reads_alone() {
        let want = Some(("header.json".to_string(), b"{\"a\": 1}".to_vec()));
        for bytes in [write(&sample()), write_with(&sample(), 0)] {
            assert_eq!(first_member(&bytes[..], 1 << 20), want);
            // (the header's 8 bytes and no further)
            let end = bytes.windows(8).position(|w| w == b"{\"a\": 1}").unwrap() + 8;
            assert_eq!(first_member(&bytes[..end], 1 << 20), want);
            assert_eq!(first_member(&bytes[..end - 1], 1 << 20), None);
            assert_eq!(first_member(&bytes[..], 7), None);
            let mut flipped = bytes.clone();
            flipped[end - 2] ^= 1;
            assert_eq!(first_member(&flipped[..], 1 << 20), None);
        }
        assert_eq!(
            first_member(&b"not an archive at all, 30 bytes+"[..], 1 << 20),
            None
        );
    }

    #[test]
    fn a_cut_or_flipped_archive_is_refused() {
        let bytes = write(&sample());
        for cut in [1, 10, bytes.len() / 2, bytes.len() - 1] {
            assert_eq!(
                Archive::read(&bytes[..cut]).err(),
                Some(NpzError::NotAnArchive),
                "{cut}"
            );
        }
        let mut flipped = bytes.clone();
        // a byte of the array x's values
        let at = bytes
            .windows(8)
            .position(|w| w == 1.5f64.to_le_bytes())
            .unwrap();
        flipped[at] ^= 1;
        assert_eq!(
            Archive::read(&flipped).err(),
            Some(NpzError::Damaged("x.npy".into()))
        );
        // any bit of the headers and directories, plain or ZIP64
        for bytes in [write(&sample()), write_with(&sample(), 0)] {
            let data: Vec<std::ops::Range<usize>> = (Archive::read(&bytes).unwrap().members)
                .values()
                .map(|d| {
                    let start = d.as_ptr() as usize - bytes.as_ptr() as usize;
                    start..start + d.len()
                })
                .collect();
            for at in (0..bytes.len()).filter(|i| !data.iter().any(|r| r.contains(i))) {
                for bit in 0..8 {
                    let mut flipped = bytes.clone();
                    flipped[at] ^= 1 << bit;
                    assert!(Archive::read(&flipped).is_err(), "byte {at} bit {bit}");
                }
            }
        }
    }
}
