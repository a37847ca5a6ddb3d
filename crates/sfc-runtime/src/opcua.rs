//! The OPC UA server of `sfc run` (cargo feature `opcua`), built on `async-opcua`.
//!
//! Values are read from the scan's published snapshots (the [`Hub`]'s board, locked only to
//! copy an `Arc` out: the scan thread publishes with `try_lock` and never waits on a client);
//! subscriptions sample those reads at each monitored item's sampling interval. Writes go to
//! the scan thread as the monitor's `set` does and are applied at the next scan; halt,
//! continue and reset are methods that only an authenticated user may call. The node layout,
//! the type mapping and the security model are in `docs/runtime.md`, "OPC UA".

use crate::board::{ChartInfo, Command, Hub, RunState, ScanState, Section};
use crate::{OpcuaOptions, OpcuaUser};
use async_opcua::crypto::SecurityPolicy;
use async_opcua::server::address_space::{AccessLevel, MethodBuilder, ObjectBuilder, VariableBuilder};
use async_opcua::server::authenticator::{
    user_pass_security_policy_id, user_pass_security_policy_uri, AuthManager, Password, UserToken,
};
use async_opcua::server::diagnostics::NamespaceMetadata;
use async_opcua::server::node_manager::memory::{simple_node_manager, SimpleNodeManager};
use async_opcua::server::{ServerBuilder, ServerEndpoint, ServerHandle, ANONYMOUS_USER_TOKEN_ID};
use async_opcua::types::{
    DataTypeId, DataValue, Error, MessageSecurityMode, NodeId, ObjectId, ObjectTypeId, QualifiedName, StatusCode,
    UAString, UserTokenPolicy, UserTokenType, VariableTypeId, Variant,
};
use sfc_sim::Value;
use std::sync::Arc;

/// The namespace of the run's nodes.
pub const NAMESPACE: &str = "urn:sfc:run";

/// How an IEC elementary type appears in OPC UA.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UaType {
    Boolean,
    SByte,
    Byte,
    Int16,
    UInt16,
    Int32,
    UInt32,
    Int64,
    UInt64,
    Float,
    Double,
    /// TIME and LTIME: OPC UA `Duration`, a Double in milliseconds.
    Duration,
    String,
}

impl UaType {
    /// The OPC UA type of an IEC type name (`INT`, `TIME`, `STRING[20]`, …). DATE, TOD and DT
    /// are Int64 (their IEC value in the runtime's encoding); anything else unknown is a String.
    pub fn of(iec: &str) -> UaType {
        let base = iec.split(['[', '(']).next().unwrap_or(iec).trim().to_ascii_uppercase();
        match base.as_str() {
            "BOOL" => UaType::Boolean,
            "SINT" => UaType::SByte,
            "USINT" | "BYTE" => UaType::Byte,
            "INT" => UaType::Int16,
            "UINT" | "WORD" => UaType::UInt16,
            "DINT" => UaType::Int32,
            "UDINT" | "DWORD" => UaType::UInt32,
            "LINT" | "DATE" | "TOD" | "TIME_OF_DAY" | "DT" | "DATE_AND_TIME" | "LDATE" | "LTOD" | "LDT" => {
                UaType::Int64
            }
            "ULINT" | "LWORD" => UaType::UInt64,
            "REAL" => UaType::Float,
            "LREAL" => UaType::Double,
            "TIME" | "LTIME" => UaType::Duration,
            _ => UaType::String,
        }
    }

    pub fn data_type(self) -> DataTypeId {
        match self {
            UaType::Boolean => DataTypeId::Boolean,
            UaType::SByte => DataTypeId::SByte,
            UaType::Byte => DataTypeId::Byte,
            UaType::Int16 => DataTypeId::Int16,
            UaType::UInt16 => DataTypeId::UInt16,
            UaType::Int32 => DataTypeId::Int32,
            UaType::UInt32 => DataTypeId::UInt32,
            UaType::Int64 => DataTypeId::Int64,
            UaType::UInt64 => DataTypeId::UInt64,
            UaType::Float => DataTypeId::Float,
            UaType::Double => DataTypeId::Double,
            UaType::Duration => DataTypeId::Duration,
            UaType::String => DataTypeId::String,
        }
    }

    /// A runtime value as a variant of this type (a value out of the type's range, which the
    /// runtime's typed memory does not hold, saturates).
    pub fn variant(self, v: &Value) -> Variant {
        let int = || match v {
            Value::Int(i) | Value::Time(i) => *i,
            Value::Bool(b) => i64::from(*b),
            Value::Real(r) => *r as i64,
            Value::Str(_) => 0,
        };
        let real = || match v {
            Value::Real(r) => *r,
            Value::Int(i) | Value::Time(i) => *i as f64,
            Value::Bool(b) => f64::from(u8::from(*b)),
            Value::Str(_) => 0.0,
        };
        let sat = |lo: i64, hi: i64| int().clamp(lo, hi);
        match self {
            UaType::Boolean => Variant::Boolean(v.as_bool().unwrap_or(int() != 0)),
            UaType::SByte => Variant::SByte(sat(i8::MIN.into(), i8::MAX.into()) as i8),
            UaType::Byte => Variant::Byte(sat(0, u8::MAX.into()) as u8),
            UaType::Int16 => Variant::Int16(sat(i16::MIN.into(), i16::MAX.into()) as i16),
            UaType::UInt16 => Variant::UInt16(sat(0, u16::MAX.into()) as u16),
            UaType::Int32 => Variant::Int32(sat(i32::MIN.into(), i32::MAX.into()) as i32),
            UaType::UInt32 => Variant::UInt32(sat(0, u32::MAX.into()) as u32),
            UaType::Int64 => Variant::Int64(int()),
            // ULINT values above i64::MAX are held as their two's complement bits.
            UaType::UInt64 => Variant::UInt64(int() as u64),
            UaType::Float => Variant::Float(real() as f32),
            UaType::Double => Variant::Double(real()),
            UaType::Duration => Variant::Double(match v {
                Value::Time(us) => *us as f64 / 1000.0,
                _ => real(),
            }),
            UaType::String => Variant::String(match v {
                Value::Str(s) => UAString::from(&**s),
                other => UAString::from(crate::protocol::value_json(other).to_string()),
            }),
        }
    }

    /// A written variant as the JSON value the scan thread's `set` takes, or `BadTypeMismatch`
    /// for a variant of another type than the node's.
    pub fn written(self, v: &Variant) -> Result<serde_json::Value, StatusCode> {
        use serde_json::json;
        Ok(match (self, v) {
            (UaType::Boolean, Variant::Boolean(b)) => json!(b),
            (UaType::SByte, Variant::SByte(i)) => json!(i),
            (UaType::Byte, Variant::Byte(i)) => json!(i),
            (UaType::Int16, Variant::Int16(i)) => json!(i),
            (UaType::UInt16, Variant::UInt16(i)) => json!(i),
            (UaType::Int32, Variant::Int32(i)) => json!(i),
            (UaType::UInt32, Variant::UInt32(i)) => json!(i),
            (UaType::Int64, Variant::Int64(i)) => json!(i),
            (UaType::UInt64, Variant::UInt64(i)) => json!(*i as i64),
            (UaType::Float, Variant::Float(r)) if r.is_finite() => json!(r),
            (UaType::Double, Variant::Double(r)) if r.is_finite() => json!(r),
            (UaType::Duration, Variant::Double(ms)) if ms.is_finite() => {
                json!(crate::protocol::value_json(&Value::Time((ms * 1000.0).round() as i64)))
            }
            (UaType::String, Variant::String(s)) => json!(s.as_ref()),
            _ => return Err(StatusCode::BadTypeMismatch),
        })
    }
}

/// Checks the options before anything is bound: SecurityPolicy None only on loopback, and
/// some way in (None, a user, or anonymous reading).
pub fn check(o: &OpcuaOptions) -> Result<(), String> {
    if o.allow_none && !o.addr.ip().is_loopback() {
        return Err(format!(
            "--opcua-allow-none serves without security: only on a loopback address, not {} \
             (use Basic256Sha256 with `[[opcua.user]]` for a network endpoint)",
            o.addr.ip()
        ));
    }
    if !o.allow_none && o.users.is_empty() && !o.anonymous_read {
        return Err("OPC UA has no way in: give `[[opcua.user]]` entries in the run configuration, \
                    `anonymous_read = true` under [opcua], or --opcua-allow-none on loopback"
            .into());
    }
    for u in &o.users {
        argon2::PasswordHash::new(&u.password_hash)
            .map_err(|e| format!("[[opcua.user]] `{}`: password_hash is not an argon2 hash ({e})", u.name))?;
    }
    Ok(())
}

/// Makes an argon2id PHC string of `password` (`sfc run --hash-password`).
pub fn hash_password(password: &str) -> Result<String, String> {
    use argon2::password_hash::{PasswordHasher, SaltString};
    let mut salt = [0u8; 16];
    getrandom::fill(&mut salt).map_err(|e| format!("no entropy for a salt: {e}"))?;
    let salt = SaltString::encode_b64(&salt).map_err(|e| e.to_string())?;
    argon2::Argon2::default()
        .hash_password(password.as_bytes(), &salt)
        .map(|h| h.to_string())
        .map_err(|e| e.to_string())
}

fn verify(hash: &str, password: &str) -> bool {
    use argon2::password_hash::PasswordVerifier;
    argon2::PasswordHash::new(hash)
        .is_ok_and(|h| argon2::Argon2::default().verify_password(password.as_bytes(), &h).is_ok())
}

/// Users and who may do what.
struct Access {
    users: Vec<OpcuaUser>,
    allow_none: bool,
    anonymous_read: bool,
}

#[async_trait::async_trait]
impl AuthManager for Access {
    async fn authenticate_anonymous_token(&self, endpoint: &ServerEndpoint) -> Result<(), Error> {
        if endpoint.user_token_ids.contains(ANONYMOUS_USER_TOKEN_ID) {
            Ok(())
        } else {
            Err(Error::new(StatusCode::BadIdentityTokenRejected, "anonymous access is off on this endpoint"))
        }
    }

    async fn authenticate_username_identity_token(
        &self,
        _endpoint: &ServerEndpoint,
        username: &str,
        password: &Password,
    ) -> Result<UserToken, Error> {
        let hash = self.users.iter().find(|u| u.name == username).map(|u| u.password_hash.clone());
        let password = password.get().to_string();
        // argon2 is slow on purpose: off the network threads.
        let ok = match hash {
            Some(h) => tokio::task::spawn_blocking(move || verify(&h, &password)).await.unwrap_or(false),
            None => false,
        };
        if ok {
            Ok(UserToken(format!("user:{username}")))
        } else {
            Err(Error::new(StatusCode::BadUserAccessDenied, format!("cannot authenticate `{username}`")))
        }
    }

    fn effective_user_access_level(&self, token: &UserToken, level: AccessLevel, _node: &NodeId) -> AccessLevel {
        // Anonymous writes only in the local-tool mode (--opcua-allow-none, loopback).
        if token.is_anonymous() && !self.allow_none {
            level - AccessLevel::CURRENT_WRITE
        } else {
            level
        }
    }

    fn is_user_executable(&self, token: &UserToken, _method: &NodeId) -> bool {
        !token.is_anonymous()
    }

    fn user_token_policies(&self, endpoint: &ServerEndpoint) -> Vec<UserTokenPolicy> {
        let mut out = Vec::new();
        if endpoint.user_token_ids.contains(ANONYMOUS_USER_TOKEN_ID) {
            out.push(UserTokenPolicy {
                policy_id: UAString::from("anonymous"),
                token_type: UserTokenType::Anonymous,
                issued_token_type: UAString::null(),
                issuer_endpoint_url: UAString::null(),
                security_policy_uri: UAString::null(),
            });
        }
        if !self.users.is_empty() {
            out.push(UserTokenPolicy {
                policy_id: user_pass_security_policy_id(endpoint),
                token_type: UserTokenType::UserName,
                issued_token_type: UAString::null(),
                issuer_endpoint_url: UAString::null(),
                security_policy_uri: user_pass_security_policy_uri(endpoint),
            });
        }
        let _ = self.anonymous_read;
        out
    }
}

/// A built server, ready to run on the network threads.
pub struct Side {
    server: async_opcua::server::Server,
    handle: ServerHandle,
    listener: std::net::TcpListener,
}

fn nid(ns: u16, path: &str) -> NodeId {
    NodeId::new(ns, path.to_string())
}

/// The latest published state (`None` before the first scan).
fn latest(hub: &Hub) -> Option<Arc<ScanState>> {
    hub.lock().history.back().cloned()
}

fn good(v: impl Into<Variant>) -> Result<DataValue, StatusCode> {
    Ok(DataValue::new_now(v.into()))
}

/// Builds the server and its address space for the run of `hub`.
pub fn build(hub: &Arc<Hub>, o: &OpcuaOptions, listener: std::net::TcpListener) -> Result<Side, String> {
    let port = listener.local_addr().map_err(|e| e.to_string())?.port();
    let host = o.addr.ip().to_string();
    let url = format!("opc.tcp://{host}:{port}/");
    let mut anonymous_ids = Vec::new();
    if o.allow_none || o.anonymous_read {
        anonymous_ids.push(ANONYMOUS_USER_TOKEN_ID.to_string());
    }
    let mut builder = ServerBuilder::new()
        .application_name(format!("sfc run {}", hub.info.pou))
        .application_uri(format!("urn:sfc:run:{}", hub.info.pou))
        .product_uri("urn:sfc")
        .host(host)
        .port(port)
        .discovery_urls(vec![url])
        .pki_dir(o.pki_dir.clone())
        .create_sample_keypair(true)
        .certificate_path("own/cert.der")
        .private_key_path("private/private.pem")
        .trust_client_certs(false)
        .check_cert_time(true)
        .with_authenticator(Arc::new(Access {
            users: o.users.clone(),
            allow_none: o.allow_none,
            anonymous_read: o.anonymous_read,
        }))
        .with_node_manager(simple_node_manager(
            NamespaceMetadata { namespace_uri: NAMESPACE.to_owned(), ..Default::default() },
            "sfc",
        ))
        .add_endpoint(
            "basic256sha256_sign",
            ServerEndpoint::new("/", SecurityPolicy::Basic256Sha256, MessageSecurityMode::Sign, &anonymous_ids),
        )
        .add_endpoint(
            "basic256sha256_sign_encrypt",
            ServerEndpoint::new(
                "/",
                SecurityPolicy::Basic256Sha256,
                MessageSecurityMode::SignAndEncrypt,
                &anonymous_ids,
            ),
        );
    if o.allow_none {
        let mut none = ServerEndpoint::new_none("/", &[ANONYMOUS_USER_TOKEN_ID.to_string()]);
        // A password sent over the None endpoint is still encrypted with the server's key.
        none.password_security_policy = Some(SecurityPolicy::Basic256Sha256.to_str().to_string());
        builder = builder.add_endpoint("none", none);
    }
    let (server, handle) = builder.build().map_err(|e| format!("cannot start the OPC UA server: {e}"))?;
    let manager = handle
        .node_managers()
        .get_of_type::<SimpleNodeManager>()
        .ok_or("cannot start the OPC UA server: its node manager is missing")?;
    let ns = handle.get_namespace_index(NAMESPACE).ok_or("cannot start the OPC UA server: no namespace")?;
    populate(hub, &manager, ns);
    Ok(Side { server, handle, listener })
}

/// The node layout (`docs/runtime.md`, "OPC UA"): `Objects/<POU>/{Inputs,Outputs,Locals,
/// Globals}/<variable>`, `Objects/<POU>/Chart/{Steps,Transitions}`, `Objects/<POU>/Runtime`.
fn populate(hub: &Arc<Hub>, manager: &Arc<SimpleNodeManager>, ns: u16) {
    let info: &ChartInfo = &hub.info;
    let pou = info.pou.clone();
    let root = nid(ns, &pou);
    let cbs = manager.inner();
    let space = manager.address_space();
    let mut space = space.write();
    ObjectBuilder::new(&root, QualifiedName::new(ns, pou.as_str()), pou.as_str())
        .organized_by(ObjectId::ObjectsFolder)
        .has_type_definition(ObjectTypeId::BaseObjectType)
        .insert(&mut *space);
    let folder =
        |space: &mut async_opcua::server::address_space::AddressSpace, id: &NodeId, name: &str, parent: &NodeId| {
            ObjectBuilder::new(id, QualifiedName::new(ns, name), name)
                .is_folder()
                .organized_by(parent.clone())
                .insert(space);
        };
    let property = |space: &mut async_opcua::server::address_space::AddressSpace,
                    parent: &NodeId,
                    name: &str,
                    value: Variant,
                    ty: DataTypeId| {
        let id = NodeId::new(ns, format!("{}.{name}", parent.identifier));
        VariableBuilder::new(&id, QualifiedName::new(ns, name), name)
            .property_of(parent.clone())
            .has_type_definition(VariableTypeId::PropertyType)
            .data_type(ty)
            .value(value)
            .access_level(AccessLevel::CURRENT_READ)
            .user_access_level(AccessLevel::CURRENT_READ)
            .insert(space);
    };
    for section in [Section::Input, Section::Output, Section::Local, Section::Global] {
        let members: Vec<usize> =
            info.variables.iter().enumerate().filter(|(_, v)| v.section == section).map(|(i, _)| i).collect();
        if members.is_empty() {
            continue;
        }
        let fid = nid(ns, &format!("{pou}.{}", section.name()));
        folder(&mut space, &fid, section.name(), &root);
        for i in members {
            let Some(var) = info.variables.get(i) else { continue };
            let ty = UaType::of(&var.ty);
            let id = nid(ns, &format!("{pou}.{}", var.name));
            let level = if section == Section::Output || !info.control {
                AccessLevel::CURRENT_READ
            } else {
                AccessLevel::CURRENT_READ | AccessLevel::CURRENT_WRITE
            };
            VariableBuilder::new(&id, QualifiedName::new(ns, var.name.as_str()), var.name.as_str())
                .organized_by(fid.clone())
                .has_type_definition(VariableTypeId::BaseDataVariableType)
                .data_type(ty.data_type())
                .value(ty.variant(&Value::Int(0)))
                .access_level(level)
                // An output's user level lets the write reach the callback, which answers
                // BadNotWritable (the stack itself would answer BadUserAccessDenied).
                .user_access_level(if info.control {
                    AccessLevel::CURRENT_READ | AccessLevel::CURRENT_WRITE
                } else {
                    level
                })
                .minimum_sampling_interval(0.0)
                .insert(&mut *space);
            property(&mut space, &id, "IecType", Variant::from(var.ty.as_str()), DataTypeId::String);
            if let Some(at) = &var.location {
                property(&mut space, &id, "Address", Variant::from(at.as_str()), DataTypeId::String);
            }
            let h = hub.clone();
            cbs.add_read_callback(id.clone(), move |_, _, _| {
                let st = latest(&h).ok_or(StatusCode::BadWaitingForInitialData)?;
                let v = st.values.get(i).ok_or(StatusCode::BadWaitingForInitialData)?;
                good(ty.variant(v))
            });
            let h = hub.clone();
            cbs.add_write_callback(id, move |dv, range| {
                if section == Section::Output {
                    return StatusCode::BadNotWritable;
                }
                if !matches!(range, async_opcua::types::NumericRange::None) {
                    return StatusCode::BadIndexRangeInvalid;
                }
                let Some(v) = dv.value.as_ref() else { return StatusCode::BadNothingToDo };
                let value = match ty.written(v) {
                    Ok(j) => j,
                    Err(s) => return s,
                };
                send(&h, Command::Set { var: i as u32, value })
            });
        }
    }
    // The chart: steps with X and T, transitions with their guard.
    let chart = nid(ns, &format!("{pou}.Chart"));
    ObjectBuilder::new(&chart, QualifiedName::new(ns, "Chart"), "Chart")
        .component_of(root.clone())
        .has_type_definition(ObjectTypeId::BaseObjectType)
        .insert(&mut *space);
    let steps = nid(ns, &format!("{pou}.Chart.Steps"));
    folder(&mut space, &steps, "Steps", &chart);
    for (s, (name, initial)) in info.steps.iter().enumerate() {
        let sid = nid(ns, &format!("{pou}.Steps.{name}"));
        ObjectBuilder::new(&sid, QualifiedName::new(ns, name.as_str()), name.as_str())
            .organized_by(steps.clone())
            .has_type_definition(ObjectTypeId::BaseObjectType)
            .insert(&mut *space);
        property(&mut space, &sid, "Initial", Variant::Boolean(*initial), DataTypeId::Boolean);
        let x = nid(ns, &format!("{pou}.Steps.{name}.X"));
        let t = nid(ns, &format!("{pou}.Steps.{name}.T"));
        for (id, bn, ty, init) in [
            (&x, "X", DataTypeId::Boolean, Variant::Boolean(false)),
            (&t, "T", DataTypeId::Duration, Variant::Double(0.0)),
        ] {
            VariableBuilder::new(id, QualifiedName::new(ns, bn), bn)
                .component_of(sid.clone())
                .has_type_definition(VariableTypeId::BaseDataVariableType)
                .data_type(ty)
                .value(init)
                .access_level(AccessLevel::CURRENT_READ)
                .user_access_level(AccessLevel::CURRENT_READ)
                .minimum_sampling_interval(0.0)
                .insert(&mut *space);
        }
        let s = s as u32;
        let h = hub.clone();
        cbs.add_read_callback(x, move |_, _, _| {
            let st = latest(&h).ok_or(StatusCode::BadWaitingForInitialData)?;
            good(st.active.iter().any(|a| a.0 == s))
        });
        let h = hub.clone();
        cbs.add_read_callback(t, move |_, _, _| {
            let st = latest(&h).ok_or(StatusCode::BadWaitingForInitialData)?;
            // T of an inactive step is 0 (IEC 61131-3 keeps the last value; the runtime does
            // not publish it).
            let us = st.active.iter().find(|a| a.0 == s).map_or(0, |a| a.1);
            good(Variant::Double(us as f64 / 1000.0))
        });
    }
    let transitions = nid(ns, &format!("{pou}.Chart.Transitions"));
    folder(&mut space, &transitions, "Transitions", &chart);
    for (t, (name, from, to)) in info.transitions.iter().enumerate() {
        let tid = nid(ns, &format!("{pou}.Transitions.{name}"));
        ObjectBuilder::new(&tid, QualifiedName::new(ns, name.as_str()), name.as_str())
            .organized_by(transitions.clone())
            .has_type_definition(ObjectTypeId::BaseObjectType)
            .insert(&mut *space);
        let names = |l: &[u32]| -> Vec<UAString> { l.iter().map(|s| UAString::from(info.step_name(*s))).collect() };
        property(&mut space, &tid, "From", Variant::from(names(from)), DataTypeId::String);
        property(&mut space, &tid, "To", Variant::from(names(to)), DataTypeId::String);
        let g = nid(ns, &format!("{pou}.Transitions.{name}.Guard"));
        VariableBuilder::new(&g, QualifiedName::new(ns, "Guard"), "Guard")
            .component_of(tid.clone())
            .has_type_definition(VariableTypeId::BaseDataVariableType)
            .data_type(DataTypeId::Boolean)
            .value(false)
            .access_level(AccessLevel::CURRENT_READ)
            .user_access_level(AccessLevel::CURRENT_READ)
            .minimum_sampling_interval(0.0)
            .insert(&mut *space);
        let t = t as u32;
        let h = hub.clone();
        cbs.add_read_callback(g, move |_, _, _| {
            let st = latest(&h).ok_or(StatusCode::BadWaitingForInitialData)?;
            match st.guards.iter().find(|g| g.0 == t) {
                Some((_, Some(b))) => good(*b),
                // The guard faulted in this scan.
                Some((_, None)) => Err(StatusCode::BadInternalError),
                // Only the guards of enabled transitions (their steps active) are evaluated.
                None => Ok(DataValue { status: Some(StatusCode::GoodNoData), ..DataValue::new_now(Variant::Empty) }),
            }
        });
    }
    // The runtime: state, scan count, jitter, and the methods.
    let rt = nid(ns, &format!("{pou}.Runtime"));
    ObjectBuilder::new(&rt, QualifiedName::new(ns, "Runtime"), "Runtime")
        .component_of(root.clone())
        .has_type_definition(ObjectTypeId::BaseObjectType)
        .insert(&mut *space);
    type Reader = Box<dyn Fn(&Hub) -> Variant + Send + Sync>;
    let figures: Vec<(&str, DataTypeId, Reader)> = vec![
        ("State", DataTypeId::String, Box::new(|h: &Hub| Variant::from(h.lock().state.name()))),
        ("Halted", DataTypeId::Boolean, Box::new(|h: &Hub| Variant::Boolean(h.lock().halted))),
        (
            "ScanCount",
            DataTypeId::UInt64,
            Box::new(|h: &Hub| Variant::UInt64(h.lock().history.back().map_or(0, |s| s.scan))),
        ),
        ("PeriodMs", DataTypeId::Duration, Box::new(|h: &Hub| Variant::Double(h.info.period as f64 / 1000.0))),
        ("JitterP50Us", DataTypeId::UInt64, Box::new(|h: &Hub| Variant::UInt64(digest(h, |d| d.jitter[0])))),
        ("JitterP99Us", DataTypeId::UInt64, Box::new(|h: &Hub| Variant::UInt64(digest(h, |d| d.jitter[1])))),
        ("JitterMaxUs", DataTypeId::UInt64, Box::new(|h: &Hub| Variant::UInt64(digest(h, |d| d.jitter[2])))),
        ("Overruns", DataTypeId::UInt64, Box::new(|h: &Hub| Variant::UInt64(digest(h, |d| d.overruns)))),
    ];
    for (name, ty, read) in figures {
        let id = nid(ns, &format!("{pou}.Runtime.{name}"));
        VariableBuilder::new(&id, QualifiedName::new(ns, name), name)
            .component_of(rt.clone())
            .has_type_definition(VariableTypeId::BaseDataVariableType)
            .data_type(ty)
            .access_level(AccessLevel::CURRENT_READ)
            .user_access_level(AccessLevel::CURRENT_READ)
            .minimum_sampling_interval(0.0)
            .insert(&mut *space);
        let h = hub.clone();
        cbs.add_read_callback(id, move |_, _, _| good(read(&h)));
    }
    if info.control {
        for name in ["Halt", "Continue", "Reset"] {
            let id = nid(ns, &format!("{pou}.Runtime.{name}"));
            MethodBuilder::new(&id, QualifiedName::new(ns, name), name)
                .component_of(rt.clone())
                .executable(true)
                .user_executable(true)
                .insert(&mut *space);
            let h = hub.clone();
            cbs.add_method_callback(id, move |_| {
                let state = h.lock().state;
                let command = match name {
                    "Halt" => Command::Halt,
                    "Continue" if state != RunState::Run => return Err(StatusCode::BadInvalidState),
                    "Continue" => Command::Continue,
                    _ => Command::Reset { cold: false },
                };
                match send(&h, command) {
                    s if s.is_good() => Ok(Vec::new()),
                    s => Err(s),
                }
            });
        }
    }
}

fn digest(h: &Hub, f: impl Fn(&crate::jitter::StatsDigest) -> u64) -> u64 {
    h.lock().digest.as_ref().map_or(0, f)
}

/// Hands a command to the scan thread (applied at the next scan); the reply is not awaited.
fn send(hub: &Hub, command: Command) -> StatusCode {
    let (reply, _) = tokio::sync::mpsc::channel(1);
    if hub.send(crate::board::Request { id: serde_json::Value::Null, command, reply }) {
        StatusCode::Good
    } else {
        StatusCode::BadShutdown
    }
}

/// Serves until the run closes.
pub async fn serve(side: Side, hub: Arc<Hub>) {
    let listener = match tokio::net::TcpListener::from_std(side.listener) {
        Ok(l) => l,
        Err(e) => {
            hub.notice(format!("sfc run: OPC UA cannot listen: {e}"));
            return;
        }
    };
    let handle = side.handle.clone();
    let h = hub.clone();
    tokio::spawn(async move {
        while !h.closing() {
            tokio::time::sleep(std::time::Duration::from_millis(20)).await;
        }
        handle.cancel();
    });
    if let Err(e) = side.server.run_with(listener).await {
        hub.notice(format!("sfc run: the OPC UA server stopped: {e}"));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iec_types_map_to_opc_ua_types() {
        assert_eq!(UaType::of("BOOL"), UaType::Boolean);
        assert_eq!(UaType::of("INT"), UaType::Int16);
        assert_eq!(UaType::of("udint"), UaType::UInt32);
        assert_eq!(UaType::of("TIME"), UaType::Duration);
        assert_eq!(UaType::of("STRING[20]"), UaType::String);
        assert_eq!(UaType::Duration.variant(&Value::Time(1500)), Variant::Double(1.5));
        assert_eq!(UaType::Int16.variant(&Value::Int(70000)), Variant::Int16(i16::MAX));
        assert_eq!(UaType::Boolean.written(&Variant::Boolean(true)), Ok(serde_json::json!(true)));
        assert_eq!(UaType::Boolean.written(&Variant::Int16(1)), Err(StatusCode::BadTypeMismatch));
        assert_eq!(UaType::Duration.written(&Variant::Double(2.0)), Ok(serde_json::json!("T#2ms")));
    }

    #[test]
    fn a_hash_verifies_its_password_only() {
        let h = hash_password("s3cret").expect("hash");
        assert!(h.starts_with("$argon2"));
        assert!(verify(&h, "s3cret"));
        assert!(!verify(&h, "secret"));
    }
}
