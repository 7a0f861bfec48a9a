//! Binding every kernel of the step to the run's buffers, window by window.

use super::*;

/// The buffers the step binds by name: the state set's and the step's others.
pub(super) type NamedBuffers<'a> = [Vec<(String, &'a wgpu::Buffer)>; 2];

/// Binds every kernel of the step to the run's buffers and the mirrors' textures, window
/// by window where a kernel works on windows (`blocks`: the blocked buffers' bytes a
/// window).
pub(super) fn bind_all(
    device: &wgpu::Device,
    program: &Program,
    (layout, records, blocks): (&StateLayout, &[(&RecordLayout, u64)], &Blocks),
    (mirrors, windows): (&Mirrors, &WindowBindings),
    grid: &GridSort,
    (buffers, paged): (NamedBuffers, &[Paged]),
) -> Result<Bound, PowderError> {
    let mut list: Vec<(String, &wgpu::Buffer)> = buffers.into_iter().flatten().collect();
    list.push(("grid".into(), grid.params()));
    list.push(("sorted_index".into(), grid.sorted_index()));
    list.push(("cell_start".into(), grid.cell_start()));
    let refs: Vec<(&str, &wgpu::Buffer)> = list.iter().map(|(n, b)| (n.as_str(), *b)).collect();
    let textures = mirrors.view_bytes();
    let pass = |name: &str| -> Result<Pass, PowderError> {
        let kernel = program.kernel(name)?.clone();
        let groups = windows.groups(device, &kernel, (&refs, blocks), &mirrors.views(), paged)?;
        let mut bound = kernel.bound_bytes(&refs, &textures);
        // the state: the fields the kernel's accessors touch, not the whole buffers
        for (name, bytes) in &mut bound {
            if let Some(b) = Buffer::ALL.into_iter().find(|b| b.name() == name) {
                *bytes = layout.touched_bytes(b, &kernel.calls);
            }
            // and the records: the fields it touches (of every layout living in the buffer)
            let mut living = records.iter().filter(|(r, _)| r.array() == name).peekable();
            if living.peek().is_some() {
                *bytes = living
                    .map(|(r, capacity)| r.touched_bytes(&kernel.calls, *capacity))
                    .sum();
            }
        }
        Ok(Pass {
            kernel,
            groups,
            bound,
        })
    };
    let optional = |name: &str| program.kernels.contains_key(name).then(|| pass(name));
    Ok(Bound {
        kick_drift: pass("kick_drift")?,
        decide: pass("decide")?,
        decide_lean: pass("decide_lean")?,
        gather: pass("gather")?,
        count_neighbours: pass("count_neighbours")?,
        neighbours: pass("neighbours")?,
        commit: pass("commit")?,
        remap: pass("remap")?,
        copy_back_history: pass("copy_back_history")?,
        force: pass("force")?,
        kick: pass("kick")?,
        collect_kick_drift: pass("collect_kick_drift")?,
        collect: pass("collect")?,
        wall_move: optional("wall_move").transpose()?,
        wall_servo: optional("wall_servo").transpose()?,
        wall_servo_apply: optional("wall_servo_apply").transpose()?,
        appear: optional("appear").transpose()?,
    })
}
