//! Security of a site (docs/distribution.md, "Security"): links in TLS with mutual
//! authentication, Zenoh access control over who may call this site's methods, and what
//! happens to a malformed payload (counted, shown, dropped).
//!
//! - TLS: `tls_ca`, `tls_cert`, `tls_key` (PEM files) make every link of the site a TLS
//!   link on which both ends show a certificate signed by the CA; a peer without one never
//!   joins. Endpoints must then be `tls/HOST:PORT`.
//! - Access control: `acl = ["alice: vehicles", "bob: vehicles.usv2"]` names, by their
//!   certificate's common name, the operators who may call methods (commands, goal writes)
//!   of this site's shared objects under a path. With an `acl`, Zenoh itself drops any
//!   other call query before it reaches the world model (the caller sees no answer:
//!   "no site answers this method"); everything else (samples, snapshots, liveliness)
//!   stays open to every authenticated peer.

use mocu_dataserver::{DataServer, Guid, Value};
use mocu_host::ModuleSpec;
use serde_json::json;
use std::path::PathBuf;

/// The PEM files of a site's mutual TLS.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Tls {
    /// The certificate authority every peer's certificate must be signed by.
    pub ca: PathBuf,
    /// This site's certificate (its common name is the operator's name under `acl`).
    pub cert: PathBuf,
    /// This site's private key.
    pub key: PathBuf,
}

/// One `acl` entry: `operator` may call methods of shared objects under `path`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Grant {
    pub operator: String,
    pub path: Vec<String>,
}

/// A site's security settings; the default is none (plain TCP, no access control).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Security {
    pub tls: Option<Tls>,
    pub acl: Vec<Grant>,
}

/// Typed errors of the security settings.
#[derive(Debug, PartialEq, Eq)]
pub enum SecurityError {
    /// Some of `tls_ca`, `tls_cert`, `tls_key` set, not all.
    PartialTls(&'static str),
    /// A file named by a `tls_*` setting that cannot be read.
    Unreadable { key: &'static str, path: PathBuf, why: String },
    /// An `acl` entry that is not `operator: path`.
    BadGrant(String),
    /// `acl` without TLS: operators are known by their certificate.
    AclWithoutTls,
    /// A non-TLS endpoint on a TLS site.
    PlainEndpoint(String),
}

impl std::fmt::Display for SecurityError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SecurityError::PartialTls(missing) => {
                write!(f, "`{missing}` is missing: TLS needs `tls_ca`, `tls_cert` and `tls_key`")
            }
            SecurityError::Unreadable { key, path, why } => {
                write!(f, "`{key}`: cannot read {}: {why}", path.display())
            }
            SecurityError::BadGrant(e) => {
                write!(
                    f,
                    "`acl` entry {e:?}: write `operator: object.path`, e.g. \"alice: vehicles\""
                )
            }
            SecurityError::AclWithoutTls => write!(
                f,
                "`acl` names operators by their certificate: it needs `tls_ca`, `tls_cert`, `tls_key`"
            ),
            SecurityError::PlainEndpoint(e) => {
                write!(f, "endpoint `{e}` is not TLS: with `tls_*` set, write `tls/HOST:PORT`")
            }
        }
    }
}

impl std::error::Error for SecurityError {}

/// Reads `acl` entries (`"alice: vehicles.usv1"`).
pub fn grants(entries: &[String]) -> Result<Vec<Grant>, SecurityError> {
    entries
        .iter()
        .map(|e| {
            let (op, path) = e.split_once(':').ok_or_else(|| SecurityError::BadGrant(e.clone()))?;
            let (op, path) = (op.trim(), crate::object_path(path.trim()));
            if op.is_empty() || op.contains(char::is_whitespace) {
                return Err(SecurityError::BadGrant(e.clone()));
            }
            Ok(Grant { operator: op.to_string(), path })
        })
        .collect()
}

/// The security settings of a `distrib` spec: `tls_ca`, `tls_cert`, `tls_key`, `acl`
/// (empty strings: not set).
pub fn from_spec(spec: &ModuleSpec) -> Result<Security, String> {
    let file = |k: &str| -> Result<Option<PathBuf>, String> {
        let s = spec.str_or(k, "").map_err(|e| e.to_string())?;
        Ok((!s.is_empty()).then(|| PathBuf::from(s)))
    };
    let files = [file("tls_ca")?, file("tls_cert")?, file("tls_key")?];
    let tls = match files {
        [None, None, None] => None,
        [Some(ca), Some(cert), Some(key)] => {
            for (k, f) in [("tls_ca", &ca), ("tls_cert", &cert), ("tls_key", &key)] {
                if !f.is_file() {
                    return Err(format!("`{k}`: no file `{}`", f.display()));
                }
            }
            Some(Tls { ca, cert, key })
        }
        [ca, cert, _] => {
            let missing = if ca.is_none() {
                "tls_ca"
            } else if cert.is_none() {
                "tls_cert"
            } else {
                "tls_key"
            };
            return Err(SecurityError::PartialTls(missing).to_string());
        }
    };
    let acl = grants(&crate::module::names(spec, "acl")?).map_err(|e| e.to_string())?;
    Ok(Security { tls, acl })
}

/// Zenoh's configuration of `security` for `site` listening on and connecting to
/// `endpoints`, as (key, JSON5 value) pairs for `insert_json5`.
pub fn zenoh_entries(
    site: &str,
    s: &Security,
    endpoints: &[String],
) -> Result<Vec<(&'static str, String)>, SecurityError> {
    let mut out = Vec::new();
    let Some(tls) = &s.tls else {
        return if s.acl.is_empty() { Ok(out) } else { Err(SecurityError::AclWithoutTls) };
    };
    if let Some(e) = endpoints.iter().find(|e| !e.starts_with("tls/")) {
        return Err(SecurityError::PlainEndpoint(e.clone()));
    }
    for (key, path) in [("tls_ca", &tls.ca), ("tls_cert", &tls.cert), ("tls_key", &tls.key)] {
        std::fs::metadata(path).map_err(|e| SecurityError::Unreadable {
            key,
            path: path.clone(),
            why: e.to_string(),
        })?;
    }
    let text = |p: &PathBuf| json!(p.to_string_lossy()).to_string();
    out.push(("transport/link/tls/root_ca_certificate", text(&tls.ca)));
    out.push(("transport/link/tls/listen_certificate", text(&tls.cert)));
    out.push(("transport/link/tls/listen_private_key", text(&tls.key)));
    out.push(("transport/link/tls/connect_certificate", text(&tls.cert)));
    out.push(("transport/link/tls/connect_private_key", text(&tls.key)));
    out.push(("transport/link/tls/enable_mtls", "true".into()));
    // Peers are known by the CA that signed them, not by a host name (loopback, NAT).
    out.push(("transport/link/tls/verify_name_on_connect", "false".into()));
    if !s.acl.is_empty() {
        out.push(("access_control", access_control(site, &s.acl).to_string()));
    }
    Ok(out)
}

/// Zenoh's `access_control` section: everything but call queries open to every peer; a
/// call query into this site only from the operators granted its object's path.
fn access_control(site: &str, acl: &[Grant]) -> serde_json::Value {
    let open = [
        "put",
        "delete",
        "declare_subscriber",
        "declare_queryable",
        "reply",
        "liveliness_token",
        "declare_liveliness_subscriber",
        "liveliness_query",
    ];
    let mine = crate::keys::chunk(site);
    let mut rules = vec![
        json!({"id": "open", "messages": open, "flows": ["ingress", "egress"],
               "permission": "allow", "key_exprs": ["**"]}),
        json!({"id": "ask", "messages": ["query"], "flows": ["egress"],
               "permission": "allow", "key_exprs": ["**"]}),
        // Snapshots, and any other query but a call into this site.
        json!({"id": "snapshots", "messages": ["query"], "flows": ["ingress"],
               "permission": "allow",
               "key_exprs": ["mocu/*/obj/**", "mocu/*/prop/**", "mocu/*/stream/**"]}),
    ];
    let mut subjects = vec![json!({"id": "anyone", "link_protocols": ["tls"]})];
    let mut policies = vec![json!({"rules": ["open", "ask", "snapshots"], "subjects": ["anyone"]})];
    for (i, g) in acl.iter().enumerate() {
        let mut key = format!("mocu/{mine}/call");
        for p in &g.path {
            key.push('/');
            key.push_str(&crate::keys::chunk(p));
        }
        key.push_str("/**");
        let (rule, subject) = (format!("call{i}"), format!("op{i}"));
        rules.push(json!({"id": rule, "messages": ["query"], "flows": ["ingress"],
                          "permission": "allow", "key_exprs": [key]}));
        subjects.push(json!({"id": subject, "cert_common_names": [g.operator]}));
        policies.push(json!({"rules": [rule], "subjects": [subject]}));
    }
    json!({"enabled": true, "default_permission": "deny",
           "rules": rules, "subjects": subjects, "policies": policies})
}

/// Counts a dropped sample in the site's status object (`malformed`) and tells the
/// operator: the first three, then each power of two, so a flood never floods the log.
pub(crate) fn report_malformed(
    ds: &DataServer,
    status: Option<Guid>,
    notify: Option<&crate::Notify>,
    count: u64,
    key: &str,
    why: &str,
) {
    if let Some(s) = status {
        let _ = ds.set(s, "malformed", Value::Int(count as i64));
    }
    if let Some(n) = notify
        && (count <= 3 || count.is_power_of_two())
    {
        n(&format!("dropped a malformed sample on `{key}`: {why} ({count} so far)"));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn acl_entries_read_as_operator_and_object_path() {
        let g = grants(&["alice: root.vehicles".into(), "bob:vehicles.usv2".into()]).unwrap();
        assert_eq!(g[0], Grant { operator: "alice".into(), path: vec!["vehicles".into()] });
        assert_eq!(g[1].path, vec!["vehicles".to_string(), "usv2".into()]);
        for bad in ["alice", ": vehicles", "al ice: vehicles"] {
            assert_eq!(grants(&[bad.into()]), Err(SecurityError::BadGrant(bad.into())), "{bad}");
        }
    }

    #[test]
    fn an_acl_needs_tls_and_a_tls_site_needs_tls_endpoints() {
        let acl = grants(&["alice: vehicles".into()]).unwrap();
        let s = Security { tls: None, acl };
        assert_eq!(zenoh_entries("a", &s, &[]), Err(SecurityError::AclWithoutTls));
        let tls = Tls { ca: "ca".into(), cert: "c".into(), key: "k".into() };
        let s = Security { tls: Some(tls), acl: Vec::new() };
        let e = zenoh_entries("a", &s, &["tcp/127.0.0.1:7447".into()]);
        assert_eq!(e, Err(SecurityError::PlainEndpoint("tcp/127.0.0.1:7447".into())));
        assert!(matches!(
            zenoh_entries("a", &s, &["tls/127.0.0.1:7447".into()]),
            Err(SecurityError::Unreadable { key: "tls_ca", .. })
        ));
    }

    #[test]
    fn a_grant_opens_call_queries_under_its_path_only_to_its_operator() {
        let acl = grants(&["alice: vehicles.usv 1".into()]).unwrap();
        let ac = access_control("adapter", &acl);
        let rules = ac["rules"].as_array().unwrap();
        let call = rules.iter().find(|r| r["id"] == "call0").unwrap();
        assert_eq!(call["key_exprs"][0], "mocu/adapter/call/vehicles/usv%201/**");
        assert_eq!(ac["subjects"][1]["cert_common_names"][0], "alice");
        assert_eq!(ac["default_permission"], "deny");
        assert!(zenoh::Config::default().insert_json5("access_control", &ac.to_string()).is_ok());
    }
}
