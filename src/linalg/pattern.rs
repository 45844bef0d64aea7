//! The symbolic side of a block factor: where L's blocks are (fill included), which block
//! updates make each column, which columns form independent components, and lists laid
//! end to end (compressed sparse rows).

/// The symbolic factor: where L's blocks are and which updates make each column.
#[derive(Debug, Clone)]
pub(crate) struct Pattern {
    /// Strictly lower blocks `L_ik` by column (with fill); each column's first slot, the
    /// identity, is unused.
    pub l_start: Vec<usize>,
    pub l_rows: Vec<usize>,
    /// The updates `S[target] −= L[source] (LD[with])ᵀ` of each column, `update_start[k]..`,
    /// `source` and `with` in the earlier column `column`.
    pub update_start: Vec<usize>,
    pub updates: Vec<Update>,
}

/// One block update of the factorization, as slots in L's layout.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Update {
    pub target: usize,
    pub source: usize,
    pub with: usize,
    pub column: usize,
}

impl Pattern {
    /// The symbolic factorisation of `n` block columns with lower blocks `lower_blocks`.
    pub fn new(n: usize, lower_blocks: &[(usize, usize)]) -> Self {
        let mut k_cols: Vec<Vec<usize>> = (0..n).map(|c| vec![c]).collect();
        for &(r, c) in lower_blocks {
            debug_assert!(r >= c, "lower blocks only");
            if r != c {
                k_cols[c].push(r);
            }
        }
        for col in &mut k_cols {
            col[1..].sort_unstable();
            col.dedup();
        }
        // The pattern of column k of L is K's plus its children's.
        let mut l_cols: Vec<Vec<usize>> = Vec::with_capacity(n);
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
        for k in 0..n {
            let mut rows: Vec<usize> = k_cols[k][1..].to_vec();
            for &j in &children[k] {
                rows.extend(l_cols[j].iter().skip(1).copied().filter(|&i| i > k));
            }
            rows.sort_unstable();
            rows.dedup();
            if let Some(&parent) = rows.first() {
                children[parent].push(k);
            }
            let mut col = vec![k];
            col.extend(rows);
            l_cols.push(col);
        }
        let (l_start, l_rows) = flatten(&l_cols);
        let mut rows_of: Vec<Vec<(usize, usize)>> = vec![Vec::new(); n];
        for j in 0..n {
            for p in l_start[j] + 1..l_start[j + 1] {
                rows_of[l_rows[p]].push((j, p));
            }
        }
        // Column k of the Schur complement: K_ik − Σ_j L_ij (L_kj D_j)ᵀ over the j with
        // L_kj ≠ 0, each a fixed slot once the pattern is known.
        let l_slot = |row: usize, col: usize| {
            let rows = &l_rows[l_start[col]..l_start[col + 1]];
            l_start[col] + rows.binary_search(&row).expect("row is in L's pattern")
        };
        let mut update_start = vec![0];
        let mut updates = Vec::new();
        for (k, entries) in rows_of.iter().enumerate() {
            for &(j, at) in entries {
                for (p, &row) in l_rows.iter().enumerate().take(l_start[j + 1]).skip(at) {
                    updates.push(Update {
                        target: l_slot(row, k),
                        source: p,
                        with: at,
                        column: j,
                    });
                }
            }
            update_start.push(updates.len());
        }
        Self {
            l_start,
            l_rows,
            update_start,
            updates,
        }
    }

    /// Number of block columns.
    pub fn columns(&self) -> usize {
        self.l_start.len() - 1
    }

    /// Number of lower blocks with fill.
    pub fn slots(&self) -> usize {
        self.l_rows.len()
    }

    /// Slot of the lower block `(row, col)`, if it is in the pattern.
    pub fn slot(&self, row: usize, col: usize) -> Option<usize> {
        let start = self.l_start[col];
        let rows = &self.l_rows[start..self.l_start[col + 1]];
        rows.binary_search(&row).ok().map(|p| start + p)
    }
}

/// The connected components of the block pattern, each its columns in order, ordered by
/// their first column.
pub(crate) fn components(n: usize, lower_blocks: &[(usize, usize)]) -> Vec<Vec<usize>> {
    fn find(root: &mut [usize], mut c: usize) -> usize {
        while root[c] != c {
            root[c] = root[root[c]];
            c = root[c];
        }
        c
    }
    let mut root: Vec<usize> = (0..n).collect();
    for &(r, c) in lower_blocks {
        let (a, b) = (find(&mut root, r), find(&mut root, c));
        root[a.max(b)] = a.min(b);
    }
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); n];
    for c in 0..n {
        let r = find(&mut root, c);
        members[r].push(c);
    }
    members.into_iter().filter(|m| !m.is_empty()).collect()
}

/// Lists laid end to end (compressed sparse rows): list `i` is
/// `items[start[i]..start[i + 1]]`.
pub(crate) fn flatten<T: Copy>(lists: &[Vec<T>]) -> (Vec<usize>, Vec<T>) {
    let mut start = Vec::with_capacity(lists.len() + 1);
    let mut items = Vec::with_capacity(lists.iter().map(Vec::len).sum());
    start.push(0);
    for list in lists {
        items.extend_from_slice(list);
        start.push(items.len());
    }
    (start, items)
}
