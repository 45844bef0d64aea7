//! Variables grouped by kind, for documentation that stays short at any size: the
//! 840,000 variables of a 60,000-bar tower fall into a few dozen kinds.

use std::collections::HashMap;

use super::Variable;

/// Variables that differ only in their indices: `cable[7].tension` is of kind
/// `cable[i].tension`, with index 7.
pub struct Kind<'a> {
    /// The first member.
    pub first: &'a Variable,
    /// The first index of each member, in table order.
    pub indices: Vec<u64>,
    /// Least and greatest start value, where the members have one.
    pub starts: Option<(f64, f64)>,
    /// Whether every member has the first one's start value.
    pub same_start: bool,
}

/// `name` with every `[digits]` written `[i]`, and the first index.
pub fn pattern(name: &str) -> (String, Option<u64>) {
    let mut out = String::with_capacity(name.len());
    let mut first = None;
    let mut rest = name;
    while let Some(open) = rest.find('[') {
        out.push_str(&rest[..=open]);
        rest = &rest[open + 1..];
        let close = rest.find(']').unwrap_or(rest.len());
        if let Ok(n) = rest[..close].parse::<u64>() {
            first.get_or_insert(n);
            out.push('i');
            rest = &rest[close..];
        }
    }
    out.push_str(rest);
    (out, first)
}

/// The kinds of `variables`, in order of first appearance.
pub fn kinds<'a>(variables: &[&'a Variable]) -> Vec<Kind<'a>> {
    let mut order: Vec<Kind<'a>> = Vec::new();
    let mut index = HashMap::new();
    for &v in variables {
        let (key, n) = pattern(&v.name);
        let key = format!(
            "{key} {:?} {:?} {:?} {:?}",
            v.causality, v.variability, v.base_type, v.unit
        );
        let k = *index.entry(key).or_insert_with(|| {
            order.push(Kind {
                first: v,
                indices: Vec::new(),
                starts: None,
                same_start: true,
            });
            order.len() - 1
        });
        let kind = &mut order[k];
        kind.indices.extend(n);
        kind.same_start &= v.start == kind.first.start;
        if let Some(s) = v.start {
            kind.starts = Some(
                kind.starts
                    .map_or((s, s), |(lo, hi)| (lo.min(s), hi.max(s))),
            );
        }
    }
    order
}

/// Indices as runs, `1..40000` or `1..3, 61..63`; past eight runs, the first eight and the
/// count of all runs.
pub fn runs(indices: &[u64]) -> String {
    let mut parts: Vec<String> = Vec::new();
    let mut k = 0;
    let mut runs = 0;
    while k < indices.len() {
        let mut end = k;
        while end + 1 < indices.len() && indices[end + 1] == indices[end] + 1 {
            end += 1;
        }
        runs += 1;
        if runs <= 8 {
            parts.push(if end > k {
                format!("{}..{}", indices[k], indices[end])
            } else {
                indices[k].to_string()
            });
        }
        k = end + 1;
    }
    if runs > 8 {
        parts.push(format!("… {} runs in all", runs));
    }
    parts.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_and_runs() {
        assert_eq!(pattern("node[61].fx"), ("node[i].fx".to_string(), Some(61)));
        assert_eq!(pattern("energy.total"), ("energy.total".to_string(), None));
        assert_eq!(pattern("a[x].b"), ("a[x].b".to_string(), None));
        assert_eq!(runs(&[1, 2, 3, 61, 62, 63]), "1..3, 61..63");
        assert_eq!(runs(&[5]), "5");
        let scattered: Vec<u64> = (0..10).map(|k| 3 * k + 1).collect();
        assert_eq!(
            runs(&scattered),
            "1, 4, 7, 10, 13, 16, 19, 22, … 10 runs in all"
        );
    }
}
