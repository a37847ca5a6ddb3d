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
    hub.latest()
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

/// The ObjectTypes of the run's namespace (async-opcua has no PLCopen nodeset).
struct Types {
    sfc: NodeId,
    step: NodeId,
    transition: NodeId,
    action: NodeId,
}

/// Defines the ObjectTypes the instance nodes point to with HasTypeDefinition, mirroring OPC
/// 30000 (PLCopen, `http://PLCopen.org/OpcUa/IEC61131-3/`): `SfcProgramType` stands for
/// `CtrlProgramType` (i=1004) and `SfcType` for `SFCType` (i=1007); OPC 30000 leaves the inside
/// of an SFC unmodelled, so `SfcStepType`, `SfcTransitionType` and `SfcActionType` are ours.
/// Each type declares its mandatory components (`docs/runtime.md`, "OPC UA").
fn define_types(space: &mut async_opcua::server::address_space::AddressSpace, ns: u16) -> Types {
    use async_opcua::server::address_space::ObjectTypeBuilder;
    use async_opcua::server::address_space::ReferenceDirection;
    use async_opcua::types::ReferenceTypeId;
    let ty = |space: &mut async_opcua::server::address_space::AddressSpace, name: &str, about: &str| {
        let id = nid(ns, &format!("type:{name}"));
        ObjectTypeBuilder::new(&id, QualifiedName::new(ns, name), name)
            .description(about)
            .subtype_of(ObjectTypeId::BaseObjectType)
            .insert(space);
        id
    };
    let member = |space: &mut async_opcua::server::address_space::AddressSpace,
                  parent: &NodeId,
                  name: &str,
                  data: Option<DataTypeId>| {
        let id = nid(ns, &format!("{}/{name}", parent.identifier));
        match data {
            Some(d) => {
                VariableBuilder::new(&id, QualifiedName::new(ns, name), name)
                    .component_of(parent.clone())
                    .has_type_definition(VariableTypeId::BaseDataVariableType)
                    .has_modelling_rule(ObjectId::ModellingRule_Mandatory)
                    .data_type(d)
                    .access_level(AccessLevel::CURRENT_READ)
                    .user_access_level(AccessLevel::CURRENT_READ)
                    .insert(space);
            }
            None => {
                ObjectBuilder::new(&id, QualifiedName::new(ns, name), name)
                    .component_of(parent.clone())
                    .has_type_definition(ObjectTypeId::FolderType)
                    .reference(
                        ObjectId::ModellingRule_Mandatory,
                        ReferenceTypeId::HasModellingRule,
                        ReferenceDirection::Forward,
                    )
                    .insert(space);
            }
        }
    };
    ty(
        space,
        "SfcProgramType",
        "A program run by sfc run: its variables by section, its Chart and its Runtime (as OPC 30000 CtrlProgramType)",
    );
    let sfc = ty(
        space,
        "SfcType",
        "A chart instance: the program's own SFC or an SFC function block instance (as OPC 30000 SFCType)",
    );
    for f in ["Steps", "Transitions", "Actions"] {
        member(space, &sfc, f, None);
    }
    for (n, d) in [
        ("LastError", DataTypeId::String),
        ("LastErrorCode", DataTypeId::Int32),
        ("LastErrorStep", DataTypeId::String),
        ("ErrorCount", DataTypeId::UInt64),
    ] {
        member(space, &sfc, n, Some(d));
    }
    let step = ty(space, "SfcStepType", "An SFC step: X (active) and T (elapsed time)");
    member(space, &step, "X", Some(DataTypeId::Boolean));
    member(space, &step, "T", Some(DataTypeId::Duration));
    let transition = ty(space, "SfcTransitionType", "An SFC transition: the value of its guard");
    member(space, &transition, "Guard", Some(DataTypeId::Boolean));
    let action = ty(space, "SfcActionType", "An SFC action: the outputs Q and A of its action control (IEC 61131-3)");
    member(space, &action, "Q", Some(DataTypeId::Boolean));
    member(space, &action, "A", Some(DataTypeId::Boolean));
    Types { sfc, step, transition, action }
}

/// The node layout (`docs/runtime.md`, "OPC UA"): `Objects/<POU>/{Inputs,Outputs,Locals,
/// Globals}/<variable>`, `Objects/<POU>/Chart/{Steps,Transitions,Actions}` and a chart per
/// SFC function block instance under `Chart`, `Objects/<POU>/Runtime`. A variable's node id is
/// its engineering name (`CarWash.StartButton`); the other nodes' ids join their levels with
/// `/`, which no IEC identifier holds (a variable named `Chart` or `Runtime` meets no other node).
fn populate(hub: &Arc<Hub>, manager: &Arc<SimpleNodeManager>, ns: u16) {
    let info: &ChartInfo = &hub.info;
    let pou = info.pou.clone();
    let root = nid(ns, &pou);
    let cbs = manager.inner();
    let space = manager.address_space();
    let mut space = space.write();
    let program_type = nid(ns, "type:SfcProgramType");
    ObjectBuilder::new(&root, QualifiedName::new(ns, pou.as_str()), pou.as_str())
        .organized_by(ObjectId::ObjectsFolder)
        .has_type_definition(program_type)
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
        let id = NodeId::new(ns, format!("{}/{name}", parent.identifier));
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
        let fid = nid(ns, &format!("{pou}/{}", section.name()));
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
    // The chart of the POU and one chart per SFC function block instance (the mechanisms),
    // each with its steps (X, T), transitions (guard) and actions (Q, A), and its error records.
    let types = define_types(&mut space, ns);
    let charts: Vec<sfc_sim::ChartOutline> = if info.charts.is_empty() {
        // A runtime without instances (the ATMT adapter): one chart of every step.
        vec![sfc_sim::ChartOutline {
            instance: pou.clone(),
            path: String::new(),
            pou: pou.clone(),
            steps: 0..info.steps.len() as u32,
            transitions: 0..info.transitions.len() as u32,
            actions: 0..info.actions.len() as u32,
        }]
    } else {
        info.charts.clone()
    };
    let chart = nid(ns, &format!("{pou}/Chart"));
    let top = charts.iter().position(|c| c.path.is_empty());
    let chart_object = |id: &NodeId, name: &str| {
        ObjectBuilder::new(id, QualifiedName::new(ns, name), name).has_type_definition(types.sfc.clone())
    };
    if top.is_some() {
        chart_object(&chart, "Chart").component_of(root.clone()).insert(&mut *space);
    } else {
        // The program itself is no chart: a folder of its mechanisms.
        ObjectBuilder::new(&chart, QualifiedName::new(ns, "Chart"), "Chart")
            .is_folder()
            .component_of(root.clone())
            .insert(&mut *space);
    }
    for (c, outline) in charts.iter().enumerate() {
        let cid = if outline.path.is_empty() {
            chart.clone()
        } else {
            let id = nid(ns, &format!("{pou}/Chart/{}", outline.path));
            chart_object(&id, &outline.path).organized_by(chart.clone()).insert(&mut *space);
            property(&mut space, &id, "FunctionBlock", Variant::from(outline.pou.as_str()), DataTypeId::String);
            id
        };
        // Names inside an instance's chart without its path (`Idle`, not `Rev.Idle`).
        let local = |q: &str| -> String {
            match q.strip_prefix(outline.path.as_str()).and_then(|r| r.strip_prefix('.')) {
                Some(r) if !outline.path.is_empty() => r.to_string(),
                _ => q.to_string(),
            }
        };
        let variable = |space: &mut async_opcua::server::address_space::AddressSpace,
                        id: &NodeId,
                        parent: &NodeId,
                        name: &str,
                        ty: DataTypeId,
                        init: Variant| {
            VariableBuilder::new(id, QualifiedName::new(ns, name), name)
                .component_of(parent.clone())
                .has_type_definition(VariableTypeId::BaseDataVariableType)
                .data_type(ty)
                .value(init)
                .access_level(AccessLevel::CURRENT_READ)
                .user_access_level(AccessLevel::CURRENT_READ)
                .minimum_sampling_interval(0.0)
                .insert(space);
        };
        let steps = nid(ns, &format!("{}/Steps", cid.identifier));
        folder(&mut space, &steps, "Steps", &cid);
        for s in outline.steps.clone() {
            let Some((name, initial)) = info.steps.get(s as usize) else { continue };
            let bn = local(name);
            let sid = nid(ns, &format!("{pou}/Steps/{name}"));
            ObjectBuilder::new(&sid, QualifiedName::new(ns, bn.as_str()), bn.as_str())
                .organized_by(steps.clone())
                .has_type_definition(types.step.clone())
                .insert(&mut *space);
            property(&mut space, &sid, "Initial", Variant::Boolean(*initial), DataTypeId::Boolean);
            let x = nid(ns, &format!("{pou}/Steps/{name}/X"));
            let t = nid(ns, &format!("{pou}/Steps/{name}/T"));
            variable(&mut space, &x, &sid, "X", DataTypeId::Boolean, Variant::Boolean(false));
            variable(&mut space, &t, &sid, "T", DataTypeId::Duration, Variant::Double(0.0));
            let h = hub.clone();
            cbs.add_read_callback(x, move |_, _, _| {
                let st = latest(&h).ok_or(StatusCode::BadWaitingForInitialData)?;
                good(st.active.iter().any(|a| a.0 == s))
            });
            let h = hub.clone();
            cbs.add_read_callback(t, move |_, _, _| {
                let st = latest(&h).ok_or(StatusCode::BadWaitingForInitialData)?;
                // An inactive step keeps the duration of its last activation (IEC 61131-3).
                let us = match st.times.get(s as usize) {
                    Some(us) => *us,
                    None => st.active.iter().find(|a| a.0 == s).map_or(0, |a| a.1),
                };
                good(Variant::Double(us as f64 / 1000.0))
            });
        }
        let transitions = nid(ns, &format!("{}/Transitions", cid.identifier));
        folder(&mut space, &transitions, "Transitions", &cid);
        for t in outline.transitions.clone() {
            let Some((name, from, to)) = info.transitions.get(t as usize) else { continue };
            let bn = local(name);
            let tid = nid(ns, &format!("{pou}/Transitions/{name}"));
            ObjectBuilder::new(&tid, QualifiedName::new(ns, bn.as_str()), bn.as_str())
                .organized_by(transitions.clone())
                .has_type_definition(types.transition.clone())
                .insert(&mut *space);
            let names =
                |l: &[u32]| -> Vec<UAString> { l.iter().map(|s| UAString::from(local(&info.step_name(*s)))).collect() };
            property(&mut space, &tid, "From", Variant::from(names(from)), DataTypeId::String);
            property(&mut space, &tid, "To", Variant::from(names(to)), DataTypeId::String);
            let g = nid(ns, &format!("{pou}/Transitions/{name}/Guard"));
            variable(&mut space, &g, &tid, "Guard", DataTypeId::Boolean, Variant::Boolean(false));
            let h = hub.clone();
            cbs.add_read_callback(g, move |_, _, _| {
                let st = latest(&h).ok_or(StatusCode::BadWaitingForInitialData)?;
                match st.guards.iter().find(|g| g.0 == t) {
                    Some((_, Some(b))) => good(*b),
                    // The guard faulted in this scan.
                    Some((_, None)) => Err(StatusCode::BadInternalError),
                    // Only the guards of enabled transitions (their steps active) are evaluated.
                    None => {
                        Ok(DataValue { status: Some(StatusCode::GoodNoData), ..DataValue::new_now(Variant::Empty) })
                    }
                }
            });
        }
        let actions = nid(ns, &format!("{}/Actions", cid.identifier));
        folder(&mut space, &actions, "Actions", &cid);
        for a in outline.actions.clone() {
            let Some((name, is_variable)) = info.actions.get(a as usize) else { continue };
            let bn = local(name);
            let aid = nid(ns, &format!("{pou}/Actions/{name}"));
            ObjectBuilder::new(&aid, QualifiedName::new(ns, bn.as_str()), bn.as_str())
                .organized_by(actions.clone())
                .has_type_definition(types.action.clone())
                .insert(&mut *space);
            let kind = if *is_variable { "variable" } else { "action" };
            property(&mut space, &aid, "Kind", Variant::from(kind), DataTypeId::String);
            for (flag, bn) in [(0usize, "Q"), (1, "A")] {
                let id = nid(ns, &format!("{pou}/Actions/{name}/{bn}"));
                variable(&mut space, &id, &aid, bn, DataTypeId::Boolean, Variant::Boolean(false));
                let h = hub.clone();
                cbs.add_read_callback(id, move |_, _, _| {
                    let st = latest(&h).ok_or(StatusCode::BadWaitingForInitialData)?;
                    let on = st.actions.iter().find(|x| x.0 == a).is_some_and(|x| if flag == 0 { x.1 } else { x.2 });
                    good(on)
                });
            }
        }
        // Error records of supervision timeouts (issue 23): the last one's text, code and step,
        // and how many were made.
        type ErrorReader = fn(&crate::board::MechanismErrors) -> Variant;
        let error_nodes: [(&str, DataTypeId, Variant, ErrorReader); 4] = [
            ("LastError", DataTypeId::String, Variant::from(""), |e| {
                Variant::from(e.last.as_ref().map(sfc_sim::ErrorRecord::message).unwrap_or_default())
            }),
            ("LastErrorCode", DataTypeId::Int32, Variant::Int32(0), |e| {
                let code = e.last.as_ref().and_then(|r| r.code).unwrap_or(0);
                Variant::Int32(code.clamp(i32::MIN.into(), i32::MAX.into()) as i32)
            }),
            ("LastErrorStep", DataTypeId::String, Variant::from(""), |e| {
                Variant::from(e.last.as_ref().map(|r| r.step.clone()).unwrap_or_default())
            }),
            ("ErrorCount", DataTypeId::UInt64, Variant::UInt64(0), |e| Variant::UInt64(e.count)),
        ];
        for (bn, ty, init, read) in error_nodes {
            let id = nid(ns, &format!("{}/{bn}", cid.identifier));
            variable(&mut space, &id, &cid, bn, ty, init);
            let h = hub.clone();
            cbs.add_read_callback(id, move |_, _, _| {
                let b = h.lock();
                let e = b.errors.get(c).cloned().unwrap_or_default();
                drop(b);
                good(read(&e))
            });
        }
    }
    // The runtime: state, scan count, jitter, and the methods.
    let rt = nid(ns, &format!("{pou}/Runtime"));
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
        let id = nid(ns, &format!("{pou}/Runtime/{name}"));
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
            let id = nid(ns, &format!("{pou}/Runtime/{name}"));
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

/// How much lower than the scan thread the OPC UA threads run (nice value, Linux).
pub const NICE: i32 = 10;

/// Runs the server on a thread of its own, with its own single-threaded tokio runtime, at a
/// lower scheduling priority (nice [`NICE`]) than the scan thread: sampling and encoding for
/// many subscriptions then take at most one core, and only what the scan leaves of it, so the
/// scan's start jitter does not follow the OPC UA load at normal priority. (The monitor and
/// Modbus keep the network threads at normal priority: Modbus carries the plant's inputs.)
pub fn spawn(side: Side, hub: Arc<Hub>) -> Result<std::thread::JoinHandle<()>, String> {
    std::thread::Builder::new()
        .name("sfc-opcua".into())
        .spawn(move || {
            lower_priority(&hub);
            let rt = tokio::runtime::Builder::new_current_thread()
                .thread_name("sfc-opcua-blocking")
                .max_blocking_threads(2)
                .on_thread_start(|| {
                    let _ = nice_this_thread();
                })
                .enable_all()
                .build();
            match rt {
                Ok(rt) => {
                    rt.block_on(serve(side, hub));
                    rt.shutdown_timeout(std::time::Duration::from_secs(1));
                }
                Err(e) => hub.notice(format!("sfc run: OPC UA cannot start its thread: {e}")),
            }
        })
        .map_err(|e| format!("cannot start the OPC UA thread: {e}"))
}

/// Lowers the calling thread's priority, saying so once when it cannot.
fn lower_priority(hub: &Hub) {
    if let Err(e) = nice_this_thread() {
        hub.notice(format!("sfc run: OPC UA runs at the scan thread's priority: {e}"));
    }
}

/// Sets the calling thread's nice value to [`NICE`] (Linux: nice values are per thread).
#[cfg(target_os = "linux")]
fn nice_this_thread() -> Result<(), String> {
    // SAFETY: plain system calls on the calling thread; gettid has no arguments.
    let r = unsafe {
        let tid = libc::syscall(libc::SYS_gettid) as libc::id_t;
        libc::setpriority(libc::PRIO_PROCESS, tid, NICE)
    };
    if r == 0 {
        Ok(())
    } else {
        Err(format!("cannot lower its priority: {}", std::io::Error::last_os_error()))
    }
}

#[cfg(not(target_os = "linux"))]
fn nice_this_thread() -> Result<(), String> {
    Err("lowering a thread's priority is implemented for Linux only".into())
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
