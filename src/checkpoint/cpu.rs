//! The CPU engine's state ([`CpuState`]) as named arrays of a checkpoint: one array per
//! state vector, the contacts as structured arrays whose columns are declared once here.

use super::npz::{Array, Member};
use super::StateError;
use crate::cpu::engine::ContactRecord;
use crate::cpu::CpuState;
use crate::model::history::HostField;
use crate::model::ContactHistory;
use glam::DVec3;

/// A contact and its key, as the CPU state lists them.
type Keyed = ((u32, u32), ContactRecord);

/// One column of a contact's row: its name and NumPy type.
#[derive(Clone, Copy)]
struct Column {
    name: &'static str,
    descr: &'static str,
    /// f64 words (a vector: 3), or bytes of an integer or flag.
    bytes: usize,
}

const fn column(name: &'static str, descr: &'static str, bytes: usize) -> Column {
    Column { name, descr, bytes }
}

/// The key's columns: (i, j), or (wall, particle) for a wall contact.
const KEY: &[Column] = &[column("i", "'<u4'", 4), column("j", "'<u4'", 4)];

/// The record's columns after the history.
const RECORD: &[Column] = &[
    column("overlap", "'<f8'", 8),
    column("normal_force", "'<f8'", 8),
    column("tangential_force", "'<f8', (3,)", 24),
    column("potential", "'<f8'", 8),
    column("friction_power", "'<f8'", 8),
    column("couple_power", "'<f8'", 8),
    column("sliding", "'|b1'", 1),
];

/// A history field's column, named as the contact network output names it.
const fn history_column(f: HostField) -> Column {
    match (f.is_flag(), f.output()) {
        (true, (name, _)) => column(name, "'|b1'", 1),
        (false, (name, 1)) => column(name, "'<f8'", 8),
        (false, (name, 3)) => column(name, "'<f8', (3,)", 24),
        _ => unreachable!(),
    }
}

// every history field is a scalar, a flag or a vector (the columns above)
const _: () = {
    let mut i = 0;
    while i < HostField::ALL.len() {
        let components = HostField::ALL[i].output().1;
        assert!(components == 1 || components == 3);
        i += 1;
    }
};

/// A contact's row: the key, the history ([`HostField::ALL`]), then the record.
fn contact_columns() -> impl Iterator<Item = Column> {
    let history = HostField::ALL.into_iter().map(history_column);
    (KEY.iter().copied())
        .chain(history)
        .chain(RECORD.iter().copied())
}

/// The structured dtype of a contact row, as `.npy` writes it.
fn contact_descr() -> String {
    let fields: Vec<String> = contact_columns()
        .map(|c| format!("('{}', {})", c.name, c.descr))
        .collect();
    format!("[{}]", fields.join(", "))
}

fn row_bytes() -> usize {
    contact_columns().map(|c| c.bytes).sum()
}

fn contacts_array(list: &[Keyed]) -> Array {
    let mut data = Vec::with_capacity(list.len() * row_bytes());
    let f = |data: &mut Vec<u8>, v: f64| data.extend(v.to_le_bytes());
    let v3 = |data: &mut Vec<u8>, v: DVec3| {
        v.to_array()
            .iter()
            .for_each(|x| data.extend(x.to_le_bytes()))
    };
    for ((i, j), r) in list {
        let h = &r.history;
        data.extend(i.to_le_bytes());
        data.extend(j.to_le_bytes());
        for field in HostField::ALL {
            let value = field.value(h);
            match (field.is_flag(), field.output().1) {
                (true, _) => data.push(u8::from(value[0] != 0.0)),
                (false, components) => value[..components].iter().for_each(|&x| f(&mut data, x)),
            }
        }
        f(&mut data, r.delta);
        f(&mut data, r.force);
        v3(&mut data, r.tangential);
        f(&mut data, r.potential);
        f(&mut data, r.friction_power);
        f(&mut data, r.couple_power);
        data.push(u8::from(r.sliding));
    }
    Array {
        descr: contact_descr(),
        shape: vec![list.len()],
        data,
    }
}

/// Reads values off a row in column order.
struct Row<'a>(&'a [u8]);

impl Row<'_> {
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let (head, rest) = self.0.split_at(N);
        self.0 = rest;
        head.try_into().unwrap_or([0; N])
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
    }
    fn f64(&mut self) -> f64 {
        f64::from_le_bytes(self.take())
    }
    fn vec3(&mut self) -> DVec3 {
        DVec3::new(self.f64(), self.f64(), self.f64())
    }
    fn flag(&mut self) -> Result<bool, StateError> {
        match self.take::<1>() {
            [0] => Ok(false),
            [1] => Ok(true),
            _ => Err(StateError("a contact flag is neither 0 nor 1".into())),
        }
    }
}

fn contacts_of(a: &Array, name: &str) -> Result<Vec<Keyed>, StateError> {
    let width = row_bytes();
    let rows_fit = a.shape.len() == 1 && a.shape[0].checked_mul(width) == Some(a.data.len());
    if a.descr != contact_descr() || !rows_fit {
        return Err(StateError(format!("`{name}` is not a table of contacts")));
    }
    let mut out = Vec::with_capacity(a.data.len() / width);
    for row in a.data.chunks_exact(width) {
        let mut r = Row(row);
        let key = (r.u32(), r.u32());
        let mut history = ContactHistory::default();
        for field in HostField::ALL {
            let mut value = [0.0; 3];
            match (field.is_flag(), field.output().1) {
                (true, _) => value[0] = f64::from(u8::from(r.flag()?)),
                (false, components) => value[..components].fill_with(|| r.f64()),
            }
            field.set(&mut history, value);
        }
        let record = ContactRecord {
            history,
            delta: r.f64(),
            force: r.f64(),
            tangential: r.vec3(),
            potential: r.f64(),
            friction_power: r.f64(),
            couple_power: r.f64(),
            sliding: r.flag()?,
        };
        out.push((key, record));
    }
    Ok(out)
}

fn vectors(v: &[DVec3]) -> Array {
    let flat: Vec<f64> = v.iter().flat_map(|x| x.to_array()).collect();
    Array {
        descr: "<f8".into(),
        shape: vec![v.len(), 3],
        data: bytemuck::cast_slice(&flat).to_vec(),
    }
}

fn flags(v: &[bool]) -> Array {
    Array::of("|b1", &v.iter().map(|&b| u8::from(b)).collect::<Vec<u8>>())
}

/// The state's arrays, in a fixed order.
pub fn arrays(s: &CpuState) -> Vec<(String, Member)> {
    let a = |name: &str, array: Array| (name.to_string(), Member::Array(array));
    vec![
        a("time", Array::scalar_f64(s.time)),
        a("steps", Array::scalar_u64(s.steps)),
        a("dt", Array::scalar_f64(s.dt)),
        a("position", vectors(&s.pos)),
        a("velocity", vectors(&s.vel)),
        a("acceleration", vectors(&s.acc)),
        a("force", vectors(&s.force)),
        a("angular_velocity", vectors(&s.omega)),
        a("torque", vectors(&s.torque)),
        a("contacts", contacts_array(&s.contacts)),
        a("wall_contacts", contacts_array(&s.wall_contacts)),
        a("dissipated", Array::scalar_f64(s.dissipated)),
        a("wall_point", vectors(&s.wall_points)),
        a("wall_velocity", vectors(&s.wall_velocities)),
        a("wall_work", Array::scalar_f64(s.wall_work)),
        a("active", flags(&s.active)),
        a("inserted", Array::scalar_f64(s.inserted)),
    ]
}

/// The state from its arrays (`get` gives each by name).
pub fn state(get: &dyn Fn(&str) -> Result<Array, StateError>) -> Result<CpuState, StateError> {
    let vec3s = |name: &str| -> Result<Vec<DVec3>, StateError> {
        let a = get(name)?;
        let v = f64s(&a, name, 2)?;
        Ok(v.chunks_exact(3)
            .map(|c| DVec3::new(c[0], c[1], c[2]))
            .collect())
    };
    let scalar = |name: &str| -> Result<f64, StateError> { Ok(f64s(&get(name)?, name, 0)?[0]) };
    let active = get("active")?;
    if active.descr != "|b1" || active.shape.len() != 1 || active.data.iter().any(|&b| b > 1) {
        return Err(StateError("`active` is not a list of flags".into()));
    }
    Ok(CpuState {
        time: scalar("time")?,
        steps: u64s(&get("steps")?, "steps")?,
        dt: scalar("dt")?,
        pos: vec3s("position")?,
        vel: vec3s("velocity")?,
        acc: vec3s("acceleration")?,
        force: vec3s("force")?,
        omega: vec3s("angular_velocity")?,
        torque: vec3s("torque")?,
        contacts: contacts_of(&get("contacts")?, "contacts")?,
        wall_contacts: contacts_of(&get("wall_contacts")?, "wall_contacts")?,
        dissipated: scalar("dissipated")?,
        wall_points: vec3s("wall_point")?,
        wall_velocities: vec3s("wall_velocity")?,
        wall_work: scalar("wall_work")?,
        active: active.data.iter().map(|&b| b == 1).collect(),
        inserted: scalar("inserted")?,
    })
}

/// The f64 values of `a`: a scalar (`dims` 0) or an (n, 3) array (`dims` 2).
pub(super) fn f64s(a: &Array, name: &str, dims: usize) -> Result<Vec<f64>, StateError> {
    let shape_ok = match dims {
        0 => a.shape.is_empty(),
        _ => a.shape.len() == 2 && a.shape[1] == 3,
    };
    let count = a.shape.iter().try_fold(8usize, |c, &d| c.checked_mul(d));
    if a.descr != "<f8" || !shape_ok || count != Some(a.data.len()) {
        return Err(StateError(format!(
            "`{name}` is not the array it should be"
        )));
    }
    Ok(a.data
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().unwrap_or([0; 8])))
        .collect())
}

/// The u64 scalar `a`.
pub(super) fn u64s(a: &Array, name: &str) -> Result<u64, StateError> {
    match (
        a.descr.as_str(),
        a.shape.as_slice(),
        a.data.as_slice().try_into(),
    ) {
        ("<u8", [], Ok(b)) => Ok(u64::from_le_bytes(b)),
        _ => Err(StateError(format!("`{name}` is not a count"))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crafted_shapes_are_refused_not_overflowed() {
        let huge = Array {
            descr: contact_descr(),
            shape: vec![(1usize << 63) + 1],
            data: vec![0; row_bytes()],
        };
        assert!(contacts_of(&huge, "contacts").is_err());
        let wide = Array {
            descr: "<f8".into(),
            shape: vec![usize::MAX / 2, 3],
            data: Vec::new(),
        };
        assert!(f64s(&wide, "position", 2).is_err());
        let short = Array {
            descr: contact_descr(),
            shape: vec![2],
            data: vec![0; row_bytes()],
        };
        assert!(contacts_of(&short, "contacts").is_err());
        let mut flag = contacts_array(&[((0, 1), ContactRecord::default())]);
        flag.data[16] = 2; // the touched flag
        assert!(contacts_of(&flag, "contacts").is_err());
    }

    /// Every field of a contact's history and record survives a checkpoint bitwise (a field
    /// added to `ContactHistory` must be named here, and then in `HostField::ALL`).
    #[test]
    fn a_contact_row_keeps_every_field() {
        let history = ContactHistory {
            delta_max: 1.5e-6,
            touched: true,
            tangential: DVec3::new(1e-7, -2e-7, 3e-7),
            rolling: DVec3::new(-4e-8, 5e-8, 6e-8),
            contact_radius: 7e-5,
            twist: -8e-9,
            slipping: true,
        };
        let record = ContactRecord {
            history,
            delta: -1e-9,
            force: 2.5e-3,
            tangential: DVec3::new(1e-4, 0.0, -1e-4),
            potential: 3e-12,
            friction_power: 4e-9,
            couple_power: 5e-10,
            sliding: true,
        };
        let list = [((3, 7), record), ((0, 2), ContactRecord::default())];
        let back = contacts_of(&contacts_array(&list), "contacts").unwrap();
        assert_eq!(back, list);
        // the columns (the order of HostField::ALL, then the record's); format 21 added
        // `slipping`
        let names: Vec<&str> = contact_columns().map(|c| c.name).collect();
        assert_eq!(
            names.join(" "),
            "i j delta_max touched tangential_spring rolling_displacement contact_radius twist \
             slipping overlap normal_force tangential_force potential friction_power \
             couple_power sliding"
        );
    }
}
