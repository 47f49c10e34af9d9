//! The key space (docs/distribution.md): where each piece of a site's world model lives.
//!
//! ```text
//! mocu/<site>/obj/<path>            an object's record (put), its deletion (delete)
//! mocu/<site>/prop/<path>/<name>    a property's value (put), its deletion (delete)
//! mocu/<site>/call/<path>/<method>  a method, called with a query
//! mocu/<site>/stream/<path>         a shared stream's messages (a camera's frames)
//! mocu/<site>/alive                 the site's liveliness token
//! ```
//!
//! `<path>` is the object's path from the root, one chunk per object name. A name keeps
//! letters, digits and `_ - . ~ + = : ,`; any other byte is written `%XX` (so `*`, `$`, `?`,
//! `#`, `/` and `@` never reach a key expression).

/// What a key names.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Key {
    Object { site: String, path: Vec<String> },
    Property { site: String, path: Vec<String>, name: String },
    Call { site: String, path: Vec<String>, method: String },
    Stream { site: String, path: Vec<String> },
    Alive { site: String },
}

fn plain(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b"_-.~+=:,".contains(&b)
}

/// One chunk of a key: `name` with every byte outside the plain set as `%XX`.
pub fn chunk(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    for &b in name.as_bytes() {
        if plain(b) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    if out.is_empty() {
        out.push('%');
    }
    out
}

/// The name a chunk stands for (`None`: not a chunk [`chunk`] writes).
pub fn unchunk(c: &str) -> Option<String> {
    if c == "%" {
        return Some(String::new());
    }
    let b = c.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = c.get(i + 1..i + 3)?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else if plain(b[i]) {
            out.push(b[i]);
            i += 1;
        } else {
            return None;
        }
    }
    String::from_utf8(out).ok()
}

fn join(site: &str, what: &str, path: &[String], last: Option<&str>) -> String {
    let mut k = format!("mocu/{}/{what}", chunk(site));
    for p in path.iter().map(String::as_str).chain(last) {
        k.push('/');
        k.push_str(&chunk(p));
    }
    k
}

pub fn object(site: &str, path: &[String]) -> String {
    join(site, "obj", path, None)
}

pub fn property(site: &str, path: &[String], name: &str) -> String {
    join(site, "prop", path, Some(name))
}

pub fn call(site: &str, path: &[String], method: &str) -> String {
    join(site, "call", path, Some(method))
}

pub fn stream(site: &str, path: &[String]) -> String {
    join(site, "stream", path, None)
}

pub fn alive(site: &str) -> String {
    format!("mocu/{}/alive", chunk(site))
}

/// A site's objects and properties, or every site's (`*`).
pub fn state_of(site: Option<&str>, what: &str) -> String {
    format!("mocu/{}/{what}/**", site.map_or("*".to_string(), chunk))
}

/// Reads a key of the key space; `None` for anything else.
pub fn parse(key: &str) -> Option<Key> {
    let mut parts = key.split('/');
    if parts.next()? != "mocu" {
        return None;
    }
    let site = unchunk(parts.next()?)?;
    let what = parts.next()?;
    let mut rest = parts.map(unchunk).collect::<Option<Vec<String>>>()?;
    Some(match what {
        "alive" if rest.is_empty() => Key::Alive { site },
        "obj" => Key::Object { site, path: rest },
        "stream" if !rest.is_empty() => Key::Stream { site, path: rest },
        "prop" => {
            let name = rest.pop()?;
            Key::Property { site, path: rest, name }
        }
        "call" => {
            let method = rest.pop()?;
            Key::Call { site, path: rest, method }
        }
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(xs: &[&str]) -> Vec<String> {
        xs.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn keys_read_back_as_what_they_name() {
        let path = p(&["vehicles", "usv 1*", "nav"]);
        assert_eq!(
            property("adapter", &path, "speed"),
            "mocu/adapter/prop/vehicles/usv%201%2A/nav/speed"
        );
        for (k, want) in [
            (object("a/b", &path), Key::Object { site: "a/b".into(), path: path.clone() }),
            (
                property("s", &path, "x#"),
                Key::Property { site: "s".into(), path: path.clone(), name: "x#".into() },
            ),
            (
                call("s", &path, "arm"),
                Key::Call { site: "s".into(), path: path.clone(), method: "arm".into() },
            ),
            (stream("s", &path), Key::Stream { site: "s".into(), path: path.clone() }),
            (alive("s"), Key::Alive { site: "s".into() }),
        ] {
            assert_eq!(parse(&k), Some(want), "{k}");
        }
    }

    #[test]
    fn keys_outside_the_key_space_are_not_read() {
        for k in [
            "other/x/obj/a",
            "mocu/s/what/a",
            "mocu/s/prop",
            "mocu/s/obj/a%zz",
            "mocu/s/obj/a*",
            "mocu/s/stream",
        ] {
            assert_eq!(parse(k), None, "{k}");
        }
    }
}
