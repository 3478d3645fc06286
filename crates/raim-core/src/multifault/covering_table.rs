/// (n, m, t, the groups' identifiable sets; satellite i is bit i).
pub(crate) static EXACT: &[(u8, u8, u8, &[u64])] = &[];
