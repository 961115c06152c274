//! Compressed-column sparsity patterns built from lists of entries, for the sparse factorizations
//! of the formulation crates (their patterns are fixed at setup and values are scattered into them).

/// Compressed-column structure from per-column row lists (sorted and deduplicated here):
/// `(col_ptr, row_idx)`.
pub fn compress_columns(mut cols: Vec<Vec<usize>>) -> (Vec<usize>, Vec<usize>) {
    let mut col_ptr = vec![0usize];
    let mut row_idx = Vec::new();
    for col in cols.iter_mut() {
        col.sort_unstable();
        col.dedup();
        row_idx.extend_from_slice(col);
        col_ptr.push(row_idx.len());
    }
    (col_ptr, row_idx)
}

/// Index in the values array of entry `(r, c)` of a compressed-column structure (which must hold it).
pub fn entry_position(col_ptr: &[usize], row_idx: &[usize], r: usize, c: usize) -> usize {
    col_ptr[c] + row_idx[col_ptr[c]..col_ptr[c + 1]].binary_search(&r).unwrap_or(0)
}
