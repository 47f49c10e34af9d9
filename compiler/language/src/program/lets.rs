//! Shared `let`s: each checked once, named by its uses ([`Node::Let`]), stored once in a
//! bundle ([`Lets`]) and taken apart without recursion.

use super::*;

/// A `let`, checked once. Its uses are [`Node::Let`] references to it, so a `let` named by
/// many others, or a chain of `let`s each naming the one before twice, costs what its
/// source does. What its uses need of it is computed here once: its constant, the paths
/// and `let`s it reads, and (when few) every path it reads through them.
#[derive(Debug)]
pub struct Let {
    /// Its number in [`Program::lets`].
    pub id: u32,
    pub name: String,
    pub value: Expr,
    /// `value.constant()`.
    pub constant: Option<Const>,
    /// The paths and `let`s the value names itself, each once, in order of appearance.
    pub reads: Vec<Read>,
    /// Every path the value reads, through its `let`s too, when there are at most
    /// [`Let::LISTED_PATHS`]; `None`: walk `reads`.
    pub paths: Option<Vec<Path>>,
    /// A digest of the name, the value and the digests of the `let`s it names: two `let`s
    /// with equal numbers and digests are equal (see [`LetRef`]'s `PartialEq`).
    pub digest: u64,
}

/// A path or a `let` an expression reads.
#[derive(Clone, Debug, PartialEq)]
pub enum Read {
    Path(Path),
    Let(LetRef),
}

impl Let {
    /// A `let` reading at most this many paths lists them all ([`Let::paths`]).
    pub const LISTED_PATHS: usize = 32;

    /// Checks nothing: `value` is checked. Computes what uses need (see [`Let`]).
    pub fn shared(id: u32, name: String, value: Expr) -> LetRef {
        let constant = value.constant();
        let reads = value.reads();
        let paths = collect_paths_upto(&reads, Let::LISTED_PATHS);
        let digest = digest(&name, &value);
        LetRef(Arc::new(Let { id, name, value, constant, reads, paths, digest }))
    }

    /// Whether the value is of a type the runtime computes once per evaluation and shares
    /// (`mocu-lower` makes it a local of the function): a number, duration, bool, string or
    /// colour, lowered ahead of its uses. A range, an object or an untyped value is lowered
    /// where it is first read instead (its uses decide what it is read as), and its depth
    /// counts there (`check_depth`).
    pub fn is_local(&self) -> bool {
        matches!(
            self.value.ty.kind,
            TypeKind::Number { .. }
                | TypeKind::Duration
                | TypeKind::Bool
                | TypeKind::String
                | TypeKind::Colour
        )
    }
}

/// Dropping the last use of the end of a chain of `let`s would drop the one before, and so
/// on, one stack frame each: a `let` being dropped hands the `let`s it names to a list
/// instead, and those that it held last are taken apart from there.
impl Drop for Let {
    fn drop(&mut self) {
        let mut pending: Vec<LetRef> = lets_of(&mut self.reads);
        let span = self.value.span;
        drop(std::mem::replace(&mut self.value, placeholder(span)));
        while let Some(l) = pending.pop() {
            if let Ok(mut last) = Arc::try_unwrap(l.0) {
                pending.extend(lets_of(&mut last.reads));
                let span = last.value.span;
                drop(std::mem::replace(&mut last.value, placeholder(span)));
            }
        }
    }
}

fn lets_of(reads: &mut Vec<Read>) -> Vec<LetRef> {
    std::mem::take(reads)
        .into_iter()
        .filter_map(|r| match r {
            Read::Let(l) => Some(l),
            Read::Path(_) => None,
        })
        .collect()
}

fn placeholder(span: Span) -> Expr {
    Expr { ty: Type::ERROR, node: Node::Bool(false), span }
}

/// A digest of a `let`'s name and value: every node in pre-order (its type, span, kind,
/// scalar contents and number of operands), a nested `let` by its number and digest. Walks
/// with a stack of its own: the checker runs on ordinary threads, and values may be as deep
/// as the parser allows.
fn digest(name: &str, value: &Expr) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = crate::passes::FastHasher::default();
    name.hash(&mut h);
    let mut stack = vec![value];
    while let Some(e) = stack.pop() {
        hash_type(&e.ty, &mut h);
        e.span.hash(&mut h);
        std::mem::discriminant(&e.node).hash(&mut h);
        // The operands go on the stack, then are turned round to be walked in order.
        let at = stack.len();
        let operands = &mut stack;
        match &e.node {
            Node::Number(x) | Node::Duration(x) => x.to_bits().hash(&mut h),
            Node::Bool(b) => b.hash(&mut h),
            Node::Str(t) | Node::Param(t) | Node::Size(t) | Node::Input(t) => t.hash(&mut h),
            Node::Colour(c) => c.hash(&mut h),
            Node::Path(p) => p.hash(&mut h),
            Node::Let(l) => (l.0.id, l.0.digest).hash(&mut h),
            Node::Index => {}
            Node::RangeEnd { range, max } => {
                max.hash(&mut h);
                operands.push(range);
            }
            Node::Range { lo, hi } => operands.extend([&**lo, &**hi]),
            Node::Unary { op, arg } => {
                std::mem::discriminant(op).hash(&mut h);
                operands.push(arg);
            }
            Node::Binary { op, lhs, rhs } => {
                std::mem::discriminant(op).hash(&mut h);
                operands.extend([&**lhs, &**rhs]);
            }
            Node::If { cond, then, other } => operands.extend([&**cond, &**then, &**other]),
            Node::Call { function, args } => {
                function.hash(&mut h);
                operands.extend(args);
            }
            Node::Format(parts) => {
                for p in parts {
                    match p {
                        FormatPart::Text(t) => t.hash(&mut h),
                        FormatPart::Value { expr, spec } => {
                            spec.hash(&mut h);
                            operands.push(expr);
                        }
                    }
                }
            }
        }
        (stack.len() - at).hash(&mut h);
        stack[at..].reverse();
    }
    h.finish()
}

/// Hashes a type by its text: interned names' keys depend on the order a process met them,
/// and a bundle is read by another process than the one that wrote it.
fn hash_type(t: &Type, h: &mut impl std::hash::Hasher) {
    use std::hash::Hash;
    std::mem::discriminant(&t.kind).hash(h);
    t.absent.hash(h);
    match t.kind {
        TypeKind::Number { unit } | TypeKind::Range { unit } => unit.map(|u| u.as_str()).hash(h),
        TypeKind::Object { object_type } => object_type.map(|o| o.as_str()).hash(h),
        _ => {}
    }
}

/// A shared reference to a [`Let`]. Equal when it is the same `let` or one with the same
/// number and digest (as after a reload or a bundle round trip); serialized as
/// `[number, digest]`, so an item's serialization changes when a `let` it reads does.
#[derive(Clone)]
pub struct LetRef(pub Arc<Let>);

impl std::ops::Deref for LetRef {
    type Target = Let;
    fn deref(&self) -> &Let {
        &self.0
    }
}

impl fmt::Debug for LetRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "let#{} {}", self.0.id, self.0.name)
    }
}

impl PartialEq for LetRef {
    fn eq(&self, other: &LetRef) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
            || (self.0.id == other.0.id && self.0.digest == other.0.digest)
    }
}

impl Serialize for LetRef {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        (self.0.id, self.0.digest).serialize(s)
    }
}

thread_local! {
    /// The `let`s of the program being deserialized on this thread, so far (see [`Lets`]).
    static READING: std::cell::RefCell<Vec<LetRef>> = const { std::cell::RefCell::new(Vec::new()) };
}

impl<'de> Deserialize<'de> for LetRef {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<LetRef, D::Error> {
        let (id, digest) = <(u32, u64)>::deserialize(d)?;
        READING.with(|r| {
            r.borrow().get(id as usize).filter(|l| l.0.digest == digest).cloned().ok_or_else(|| {
                serde::de::Error::custom(format!("`let` #{id} is not defined before its use"))
            })
        })
    }
}

/// The program's `let`s. Serialized as a list of `{name, value}`, each value naming the
/// `let`s before it by number; deserializing rebuilds them in order (they are read before
/// the rest of the program, whose uses they resolve; call [`Lets::end_reading`] once a
/// program is read, to let go of them).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Lets(pub Vec<LetRef>);

impl Lets {
    /// Forgets the `let`s of the last program deserialized on this thread.
    pub fn end_reading() {
        READING.with(|r| r.borrow_mut().clear());
    }
}

#[derive(Serialize)]
struct LetOut<'a> {
    name: &'a str,
    value: &'a Expr,
}

#[derive(Deserialize)]
struct LetIn {
    name: String,
    value: Expr,
}

impl Serialize for Lets {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeSeq;
        let mut seq = s.serialize_seq(Some(self.0.len()))?;
        for l in &self.0 {
            seq.serialize_element(&LetOut { name: &l.0.name, value: &l.0.value })?;
        }
        seq.end()
    }
}

impl<'de> Deserialize<'de> for Lets {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Lets, D::Error> {
        struct Visit;
        impl<'de> serde::de::Visitor<'de> for Visit {
            type Value = Lets;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a list of `let`s")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Lets, A::Error> {
                READING.with(|r| r.borrow_mut().clear());
                let mut out = Vec::new();
                while let Some(w) = seq.next_element::<LetIn>()? {
                    let l = Let::shared(out.len() as u32, w.name, w.value);
                    READING.with(|r| r.borrow_mut().push(l.clone()));
                    out.push(l);
                }
                Ok(Lets(out))
            }
        }
        d.deserialize_seq(Visit)
    }
}
