//! A unified diff of two texts by lines (what `mocu fmt --check` prints): Myers' algorithm
//! after the common head and tail are cut off, three lines of context, `diff -u` headers.

/// Past this many differing lines the rest is shown as removed and added whole (the
/// algorithm's memory grows with the square of the difference).
const MAX_EDITS: usize = 4000;
const CONTEXT: usize = 3;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Op {
    Equal(usize, usize),
    Delete(usize),
    Insert(usize),
}

/// `old` and `new` as a unified diff with the file names `old_name`, `new_name`; empty when
/// they are equal.
pub fn unified(old: &str, new: &str, old_name: &str, new_name: &str) -> String {
    if old == new {
        return String::new();
    }
    let a: Vec<&str> = old.split_inclusive('\n').collect();
    let b: Vec<&str> = new.split_inclusive('\n').collect();
    let ops = edits(&a, &b);
    let mut out = format!("--- {old_name}\n+++ {new_name}\n");
    let changes: Vec<usize> =
        (0..ops.len()).filter(|&k| !matches!(ops[k], Op::Equal(..))).collect();
    // Lines of each side before each op.
    let mut pos = Vec::with_capacity(ops.len() + 1);
    let (mut x, mut y) = (0, 0);
    for op in &ops {
        pos.push((x, y));
        match op {
            Op::Equal(..) => (x, y) = (x + 1, y + 1),
            Op::Delete(_) => x += 1,
            Op::Insert(_) => y += 1,
        }
    }
    let mut k = 0;
    while k < changes.len() {
        // One hunk: changes no more than two contexts apart.
        let first = changes[k];
        let mut last = first;
        while k + 1 < changes.len() && changes[k + 1] - last <= 2 * CONTEXT + 1 {
            k += 1;
            last = changes[k];
        }
        k += 1;
        let from = first.saturating_sub(CONTEXT);
        let to = (last + CONTEXT + 1).min(ops.len());
        hunk(&mut out, &ops[from..to], pos[from], &a, &b);
    }
    out
}

/// One hunk: `ops`, which start after `before` (old, new) lines.
fn hunk(out: &mut String, ops: &[Op], before: (usize, usize), a: &[&str], b: &[&str]) {
    let a_len = ops.iter().filter(|o| !matches!(o, Op::Insert(_))).count();
    let b_len = ops.iter().filter(|o| !matches!(o, Op::Delete(_))).count();
    let range = |start: usize, len: usize| match len {
        0 => format!("{start},0"),
        1 => format!("{}", start + 1),
        _ => format!("{},{len}", start + 1),
    };
    out.push_str(&format!("@@ -{} +{} @@\n", range(before.0, a_len), range(before.1, b_len)));
    for op in ops {
        let (mark, line) = match *op {
            Op::Equal(i, _) => (' ', a[i]),
            Op::Delete(i) => ('-', a[i]),
            Op::Insert(j) => ('+', b[j]),
        };
        out.push(mark);
        out.push_str(line);
        if !line.ends_with('\n') {
            out.push_str("\n\\ No newline at end of file\n");
        }
    }
}

/// The edit script turning `a` into `b`.
fn edits(a: &[&str], b: &[&str]) -> Vec<Op> {
    let head = a.iter().zip(b).take_while(|(x, y)| x == y).count();
    let tail =
        a[head..].iter().rev().zip(b[head..].iter().rev()).take_while(|(x, y)| x == y).count();
    let (am, bm) = (&a[head..a.len() - tail], &b[head..b.len() - tail]);
    let mut ops: Vec<Op> = (0..head).map(|i| Op::Equal(i, i)).collect();
    let middle = myers(am, bm).unwrap_or_else(|| {
        let mut v: Vec<Op> = (0..am.len()).map(Op::Delete).collect();
        v.extend((0..bm.len()).map(Op::Insert));
        v
    });
    ops.extend(middle.into_iter().map(|op| match op {
        Op::Equal(i, j) => Op::Equal(i + head, j + head),
        Op::Delete(i) => Op::Delete(i + head),
        Op::Insert(j) => Op::Insert(j + head),
    }));
    let (an, bn) = (a.len() - tail, b.len() - tail);
    ops.extend((0..tail).map(|k| Op::Equal(an + k, bn + k)));
    ops
}

/// Myers' shortest edit script, or `None` past [`MAX_EDITS`].
fn myers(a: &[&str], b: &[&str]) -> Option<Vec<Op>> {
    let (n, m) = (a.len() as isize, b.len() as isize);
    let max = (a.len() + b.len()).min(MAX_EDITS) as isize;
    let off = max + 1;
    let mut v = vec![0isize; (2 * off + 1) as usize];
    // trace[d]: the furthest x on each diagonal k (index k + off) before step d.
    let mut trace: Vec<Vec<isize>> = Vec::new();
    let mut found = None;
    'outer: for d in 0..=max {
        trace.push(v[(off - d) as usize..=(off + d) as usize].to_vec());
        let mut k = -d;
        while k <= d {
            let down = k == -d || (k != d && v[(k - 1 + off) as usize] < v[(k + 1 + off) as usize]);
            let mut x =
                if down { v[(k + 1 + off) as usize] } else { v[(k - 1 + off) as usize] + 1 };
            let mut y = x - k;
            while x < n && y < m && a[x as usize] == b[y as usize] {
                x += 1;
                y += 1;
            }
            v[(k + off) as usize] = x;
            if x >= n && y >= m {
                found = Some(d);
                break 'outer;
            }
            k += 2;
        }
    }
    let dmax = found?;
    // Walk back from (n, m).
    let mut ops = Vec::new();
    let (mut x, mut y) = (n, m);
    for d in (1..=dmax).rev() {
        let vd = &trace[d as usize];
        let at = |k: isize| vd[(k + d) as usize];
        let k = x - y;
        let down = k == -d || (k != d && at(k - 1) < at(k + 1));
        let pk = if down { k + 1 } else { k - 1 };
        let px = at(pk);
        let py = px - pk;
        while x > px && y > py {
            x -= 1;
            y -= 1;
            ops.push(Op::Equal(x as usize, y as usize));
        }
        if down {
            y -= 1;
            ops.push(Op::Insert(y as usize));
        } else {
            x -= 1;
            ops.push(Op::Delete(x as usize));
        }
        debug_assert!(x == px && y == py);
    }
    while x > 0 && y > 0 {
        x -= 1;
        y -= 1;
        ops.push(Op::Equal(x as usize, y as usize));
    }
    ops.reverse();
    Some(ops)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_texts_have_no_diff() {
        assert_eq!(unified("a\nb\n", "a\nb\n", "x", "y"), "");
    }

    #[test]
    fn a_changed_line_is_shown_with_three_lines_of_context() {
        let old = "1\n2\n3\n4\n5\n6\n7\n8\n9\n";
        let new = "1\n2\n3\n4\nfive\n6\n7\n8\n9\n";
        let d = unified(old, new, "a/f", "b/f");
        assert_eq!(d, "--- a/f\n+++ b/f\n@@ -2,7 +2,7 @@\n 2\n 3\n 4\n-5\n+five\n 6\n 7\n 8\n");
    }

    #[test]
    fn applying_the_script_gives_the_new_text() {
        let a: Vec<&str> = "a b c a b b a".split(' ').collect();
        let b: Vec<&str> = "c b a b a c".split(' ').collect();
        let ops = edits(&a, &b);
        let rebuilt: Vec<&str> = ops
            .iter()
            .filter_map(|op| match *op {
                Op::Equal(i, _) => Some(a[i]),
                Op::Insert(j) => Some(b[j]),
                Op::Delete(_) => None,
            })
            .collect();
        assert_eq!(rebuilt, b);
        // Myers finds the shortest script: 5 edits here.
        assert_eq!(ops.iter().filter(|o| !matches!(o, Op::Equal(..))).count(), 5);
    }

    #[test]
    fn a_line_added_at_the_end_without_a_newline_is_marked() {
        let d = unified("a\n", "a\nb", "x", "y");
        assert!(d.contains("+b\n\\ No newline at end of file\n"), "{d}");
    }
}
