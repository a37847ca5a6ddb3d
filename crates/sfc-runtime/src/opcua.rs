//! The OPC UA server of `sfc run` (cargo feature `opcua`), built on `async-opcua`.
//!
//! Values follow the scan's published states: a task reads the board ([`Hub::image`], the one
//! reading every view of the process image shares) a few times per shortest publishing
//! interval and sets the nodes whose value changed in one batch, which notifies their
//! subscribers; reads answer from the same nodes. The scan thread publishes with `try_lock` and
//! never waits on a client. Writes go to the scan thread as the monitor's `set` does and are
//! applied at the next scan; halt, continue and reset are methods. Who may write and call is
//! decided per session, from its user's role and (for anonymous sessions) its endpoint. The
//! node layout, the type mapping and the security model are in `docs/runtime.md`, "OPC UA".

use crate::board::{ChartInfo, Command, Hub, ImageView, RunState, Section};
use crate::{OpcuaOptions, OpcuaRole, OpcuaUser};
use async_opcua::crypto::SecurityPolicy;
use async_opcua::server::address_space::{AccessLevel, AddressSpace, MethodBuilder, ObjectBuilder, VariableBuilder};
use async_opcua::server::authenticator::{
    user_pass_security_policy_id, user_pass_security_policy_uri, AuthManager, Password, UserToken,
};
use async_opcua::server::diagnostics::NamespaceMetadata;
use async_opcua::server::node_manager::memory::{
    InMemoryNodeManager, InMemoryNodeManagerBuilder, InMemoryNodeManagerImpl,
};
use async_opcua::server::node_manager::{MethodCall, RequestContext, ServerContext, WriteNode};
use async_opcua::server::{ServerBuilder, ServerEndpoint, ServerHandle, SubscriptionCache, ANONYMOUS_USER_TOKEN_ID};
use async_opcua::sync::RwLock;
use async_opcua::types::{
    AttributeId, DataTypeId, DataValue, Error, MessageSecurityMode, NodeId, ObjectId, ObjectTypeId, QualifiedName,
    StatusCode, UAString, UserTokenPolicy, UserTokenType, VariableTypeId, Variant,
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

/// Who a session is and what it may do (`docs/runtime.md`, "Security").
struct Access {
    users: Vec<OpcuaUser>,
    allow_none: bool,
    anonymous_read: bool,
}

impl Access {
    /// The role of an authenticated user's token (`None` for anonymous).
    fn role_of(&self, token: &UserToken) -> Option<OpcuaRole> {
        let name = token.0.strip_prefix("user:")?;
        self.users.iter().find(|u| u.name == name).map(|u| u.role)
    }

    /// What the session of `context` may do: a user's role; an anonymous session writes
    /// only on the None endpoint (`--opcua-allow-none`, loopback), and only reads elsewhere.
    fn role(&self, context: &RequestContext) -> OpcuaRole {
        if let Some(role) = self.role_of(&context.token) {
            return role;
        }
        let mode = context.session().read().message_security_mode();
        if self.allow_none && mode == MessageSecurityMode::None {
            OpcuaRole::Operate
        } else {
            OpcuaRole::Read
        }
    }
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
        endpoint: &ServerEndpoint,
        username: &str,
        password: &Password,
    ) -> Result<UserToken, Error> {
        // async-opcua takes a password in clear when the client sends it so, and does not say
        // which it was: over the None endpoint a password could travel unencrypted, so user
        // names are taken on the secure endpoints only.
        if endpoint.security_policy() == SecurityPolicy::None {
            return Err(Error::new(
                StatusCode::BadIdentityTokenRejected,
                "user names are refused on the None endpoint (a password could travel in clear): \
                 use Basic256Sha256 Sign or SignAndEncrypt",
            ));
        }
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

    /// The UserAccessLevel clients read: no write bit for a user of role `read`, nor for an
    /// anonymous session, except when only the None endpoint admits anonymous sessions (which
    /// may write there). async-opcua does not tell this function the session's endpoint: with
    /// both `allow_none` and `anonymous_read`, anonymous sessions read no write bit, and on the
    /// None endpoint their writes still succeed ([`SfcNodes::write_value`] decides per session).
    fn effective_user_access_level(&self, token: &UserToken, level: AccessLevel, _node: &NodeId) -> AccessLevel {
        let writes = match self.role_of(token) {
            Some(role) => role >= OpcuaRole::Operate,
            None => token.is_anonymous() && self.allow_none && !self.anonymous_read,
        };
        if writes {
            level
        } else {
            level - AccessLevel::CURRENT_WRITE
        }
    }

    fn is_user_executable(&self, token: &UserToken, _method: &NodeId) -> bool {
        self.role_of(token) == Some(OpcuaRole::Admin)
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
        if !self.users.is_empty() && endpoint.security_policy() != SecurityPolicy::None {
            out.push(UserTokenPolicy {
                policy_id: user_pass_security_policy_id(endpoint),
                token_type: UserTokenType::UserName,
                issued_token_type: UAString::null(),
                issuer_endpoint_url: UAString::null(),
                security_policy_uri: user_pass_security_policy_uri(endpoint),
            });
        }
        out
    }
}

/// A node id of the run's namespace.
fn nid(ns: u16, path: &str) -> NodeId {
    NodeId::new(ns, path.to_string())
}

/// Where a published node's value comes from.
#[derive(Debug, Clone, Copy)]
enum Source {
    /// Variable `i` of [`ChartInfo::variables`].
    Var(usize, UaType),
    StepX(u32),
    StepT(u32),
    Guard(u32),
    ActionQ(u32),
    ActionA(u32),
    /// An error record node of chart instance `c`.
    Error(usize, ErrorNode),
    Runtime(RuntimeNode),
}

#[derive(Debug, Clone, Copy)]
enum ErrorNode {
    Text,
    Code,
    Step,
    Count,
}

#[derive(Debug, Clone, Copy)]
enum RuntimeNode {
    State,
    Halted,
    ScanCount,
    PeriodMs,
    JitterP50,
    JitterP99,
    JitterMax,
    Overruns,
}

/// A variable a client may write: `(variable, its type, its section)`.
type Writable = (usize, UaType, Section);

/// The run's nodes: values pushed from the board, writes and method calls checked against
/// the session's role and handed to the scan thread.
pub struct SfcNodes {
    namespace: NamespaceMetadata,
    hub: Arc<Hub>,
    access: Arc<Access>,
    /// The nodes whose values follow the run, and the writable variables and methods (filled
    /// by [`populate`]).
    table: std::sync::RwLock<Table>,
}

#[derive(Default)]
struct Table {
    published: Vec<(NodeId, Source)>,
    writable: std::collections::HashMap<NodeId, Writable>,
    methods: std::collections::HashMap<NodeId, &'static str>,
}

#[async_trait::async_trait]
impl InMemoryNodeManagerImpl for SfcNodes {
    async fn init(&self, _space: &mut AddressSpace, _context: ServerContext) {}

    fn name(&self) -> &str {
        "sfc"
    }

    fn namespaces(&self) -> Vec<NamespaceMetadata> {
        vec![self.namespace.clone()]
    }

    async fn write(
        &self,
        context: &RequestContext,
        _space: &RwLock<AddressSpace>,
        nodes_to_write: &mut [&mut WriteNode],
    ) -> Result<(), StatusCode> {
        for w in nodes_to_write {
            let status = self.write_value(context, w.value());
            w.set_status(status);
        }
        Ok(())
    }

    async fn call(
        &self,
        context: &RequestContext,
        _space: &RwLock<AddressSpace>,
        methods_to_call: &mut [&mut &mut MethodCall],
    ) -> Result<(), StatusCode> {
        for m in methods_to_call {
            let name = self.table.read().unwrap_or_else(|e| e.into_inner()).methods.get(m.method_id()).copied();
            let status = match name {
                None => StatusCode::BadMethodInvalid,
                Some(_) if self.access.role(context) < OpcuaRole::Admin => StatusCode::BadUserAccessDenied,
                Some(name) => self.method(name),
            };
            if status.is_good() {
                m.set_outputs(Vec::new());
            }
            m.set_status(status);
        }
        Ok(())
    }
}

impl SfcNodes {
    /// A client's write of a variable's value: outputs are the chart's (`BadNotWritable`), a
    /// session that may not write gets `BadUserAccessDenied`, a variant of another type
    /// `BadTypeMismatch`; a good write goes to the scan thread like the monitor's `set`.
    fn write_value(
        &self,
        context: &RequestContext,
        w: &async_opcua::server::node_manager::ParsedWriteValue,
    ) -> StatusCode {
        let target = self.table.read().unwrap_or_else(|e| e.into_inner()).writable.get(&w.node_id).copied();
        let Some((var, ty, section)) = target else { return StatusCode::BadNotWritable };
        if w.attribute_id != AttributeId::Value || section == Section::Output || !self.hub.info.control {
            return StatusCode::BadNotWritable;
        }
        if self.access.role(context) < OpcuaRole::Operate {
            return StatusCode::BadUserAccessDenied;
        }
        if !matches!(w.index_range, async_opcua::types::NumericRange::None) {
            return StatusCode::BadIndexRangeInvalid;
        }
        let Some(v) = w.value.value.as_ref() else { return StatusCode::BadNothingToDo };
        match ty.written(v) {
            Ok(value) => send(&self.hub, Command::Set { var: var as u32, value }),
            Err(s) => s,
        }
    }

    fn method(&self, name: &str) -> StatusCode {
        let state = self.hub.lock().state;
        let command = match name {
            "Halt" => Command::Halt,
            "Continue" if state != RunState::Run => return StatusCode::BadInvalidState,
            "Continue" => Command::Continue,
            _ => Command::Reset { cold: false },
        };
        send(&self.hub, command)
    }
}

/// A variable whose value the run publishes reads BadWaitingForInitialData until it does.
fn set_waiting(space: &mut AddressSpace, id: &NodeId) {
    if let Some(async_opcua::server::address_space::NodeType::Variable(v)) = space.find_mut(id) {
        v.set_data_value(DataValue {
            status: Some(StatusCode::BadWaitingForInitialData),
            ..DataValue::new_now(Variant::Empty)
        });
    }
}

/// Hands a command to the scan thread (applied at the next scan); the reply is not awaited.
fn send(hub: &Hub, command: Command) -> StatusCode {
    if hub.command(command) {
        StatusCode::Good
    } else {
        StatusCode::BadShutdown
    }
}

/// A built server, ready to run on the network threads.
pub struct Side {
    server: async_opcua::server::Server,
    handle: ServerHandle,
    listener: std::net::TcpListener,
    nodes: Arc<InMemoryNodeManager<SfcNodes>>,
    /// How often the values are brought up to date from the board.
    tick: std::time::Duration,
}

/// Makes the PKI folder private before the server uses it: the folder and its `private/` are
/// created with mode 0700, or refused when they exist and others may read them, as is a private
/// key others may read.
#[cfg(unix)]
fn private_pki(dir: &std::path::Path) -> Result<(), String> {
    use std::os::unix::fs::{DirBuilderExt, PermissionsExt};
    for d in [dir.to_path_buf(), dir.join("private")] {
        match std::fs::metadata(&d) {
            Ok(m) if !m.is_dir() => return Err(format!("the OPC UA PKI folder {} is not a folder", d.display())),
            Ok(m) if m.permissions().mode() & 0o077 != 0 => {
                return Err(format!(
                    "the OPC UA PKI folder {} can be read by other users (mode {:o}): it holds the server's \
                     private key; `chmod 700 {}` it, or name another with --opcua-pki",
                    d.display(),
                    m.permissions().mode() & 0o777,
                    d.display()
                ))
            }
            Ok(_) => {}
            Err(_) => std::fs::DirBuilder::new()
                .recursive(true)
                .mode(0o700)
                .create(&d)
                .map_err(|e| format!("cannot create the OPC UA PKI folder {}: {e}", d.display()))?,
        }
    }
    let key = private_key(dir);
    if let Ok(m) = std::fs::metadata(&key) {
        if m.permissions().mode() & 0o077 != 0 {
            return Err(format!(
                "the OPC UA private key {} can be read by other users (mode {:o}): `chmod 600 {}` it",
                key.display(),
                m.permissions().mode() & 0o777,
                key.display()
            ));
        }
    }
    Ok(())
}

/// Gives the private key the server made on its first start mode 0600 (it was written inside
/// the private folder, so no other user could reach it in between).
#[cfg(unix)]
fn private_key_mode(dir: &std::path::Path) -> Result<(), String> {
    use std::os::unix::fs::PermissionsExt;
    let key = private_key(dir);
    if key.is_file() {
        std::fs::set_permissions(&key, std::fs::Permissions::from_mode(0o600))
            .map_err(|e| format!("cannot make the OPC UA private key {} private: {e}", key.display()))?;
    }
    Ok(())
}

fn private_key(dir: &std::path::Path) -> std::path::PathBuf {
    dir.join("private/private.pem")
}

#[cfg(not(unix))]
fn private_pki(_dir: &std::path::Path) -> Result<(), String> {
    Ok(())
}

#[cfg(not(unix))]
fn private_key_mode(_dir: &std::path::Path) -> Result<(), String> {
    Ok(())
}

/// Builds the server and its address space for the run of `hub`.
pub fn build(hub: &Arc<Hub>, o: &OpcuaOptions, listener: std::net::TcpListener) -> Result<Side, String> {
    let port = listener.local_addr().map_err(|e| e.to_string())?.port();
    let host = o.addr.ip().to_string();
    let url = format!("opc.tcp://{host}:{port}/");
    private_pki(&o.pki_dir)?;
    // Anonymous sessions: on the secure endpoints only to read (`anonymous_read`); on the None
    // endpoint (`allow_none`, loopback) to read and write.
    let secure_ids = if o.anonymous_read { vec![ANONYMOUS_USER_TOKEN_ID.to_string()] } else { Vec::new() };
    let access =
        Arc::new(Access { users: o.users.clone(), allow_none: o.allow_none, anonymous_read: o.anonymous_read });
    let namespace = NamespaceMetadata { namespace_uri: NAMESPACE.to_owned(), ..Default::default() };
    let (h, a) = (hub.clone(), access.clone());
    let nodes = InMemoryNodeManagerBuilder::new(move |ctx: ServerContext, space: &mut AddressSpace| {
        let mut namespace = namespace;
        namespace.namespace_index = ctx.type_tree.write().namespaces_mut().add_namespace(&namespace.namespace_uri);
        space.add_namespace(&namespace.namespace_uri, namespace.namespace_index);
        SfcNodes { namespace, hub: h, access: a, table: Default::default() }
    });
    let min_ms = o.min_publish.as_secs_f64() * 1000.0;
    // Subscriptions are looked at, and the values brought up to date, a few times per shortest
    // publishing interval: a change reaches a subscriber within its publishing interval of the
    // state that made it (plus this tick).
    let tick = (o.min_publish / 4).clamp(std::time::Duration::from_millis(1), std::time::Duration::from_millis(25));
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
        .private_key_path(private_key(std::path::Path::new("")))
        .trust_client_certs(false)
        .check_cert_time(true)
        .subscription_poll_interval_ms(tick.as_millis().max(1) as u64)
        .with_authenticator(access.clone())
        .with_node_manager(nodes)
        .add_endpoint(
            "basic256sha256_sign",
            ServerEndpoint::new("/", SecurityPolicy::Basic256Sha256, MessageSecurityMode::Sign, &secure_ids),
        )
        .add_endpoint(
            "basic256sha256_sign_encrypt",
            ServerEndpoint::new("/", SecurityPolicy::Basic256Sha256, MessageSecurityMode::SignAndEncrypt, &secure_ids),
        );
    let limits = builder.limits_mut();
    limits.subscriptions.min_publishing_interval_ms = min_ms;
    limits.subscriptions.min_sampling_interval_ms = min_ms;
    // open62541 clients keep up to 10 publish requests outstanding per subscription.
    limits.subscriptions.max_publish_requests_per_subscription = 10;
    if o.allow_none {
        // Anonymous only: user names are taken on the secure endpoints (see Access).
        let none = ServerEndpoint::new_none("/", &[ANONYMOUS_USER_TOKEN_ID.to_string()]);
        builder = builder.add_endpoint("none", none);
    }
    let (server, handle) = builder.build().map_err(|e| format!("cannot start the OPC UA server: {e}"))?;
    private_key_mode(&o.pki_dir)?;
    let nodes = handle
        .node_managers()
        .get_of_type::<InMemoryNodeManager<SfcNodes>>()
        .ok_or("cannot start the OPC UA server: its node manager is missing")?;
    let ns = handle.get_namespace_index(NAMESPACE).ok_or("cannot start the OPC UA server: no namespace")?;
    populate(hub, &nodes, ns);
    Ok(Side { server, handle, listener, nodes, tick })
}

/// The ObjectTypes of the run's namespace (async-opcua has no PLCopen nodeset).
struct Types {
    step: NodeId,
    transition: NodeId,
    action: NodeId,
}

/// Defines the ObjectTypes the instance nodes point to with HasTypeDefinition, mirroring OPC
/// 30000 (PLCopen, `http://PLCopen.org/OpcUa/IEC61131-3/`): `SfcProgramType` stands for
/// `CtrlProgramType` (i=1004) and `SfcType` for `SFCType` (i=1007); OPC 30000 leaves the inside
/// of an SFC unmodelled, so `SfcStepType`, `SfcTransitionType` and `SfcActionType` are ours.
/// Each type declares its mandatory components (`docs/runtime.md`, "OPC UA"). A type's node id
/// is `type:<name>`, a component's `type:<name>/<component>`.
fn define_types(space: &mut AddressSpace, ns: u16) -> Types {
    use async_opcua::server::address_space::ObjectTypeBuilder;
    use async_opcua::server::address_space::ReferenceDirection;
    use async_opcua::types::ReferenceTypeId;
    let ty = |space: &mut AddressSpace, name: &str, about: &str| {
        let id = nid(ns, &format!("type:{name}"));
        ObjectTypeBuilder::new(&id, QualifiedName::new(ns, name), name)
            .description(about)
            .subtype_of(ObjectTypeId::BaseObjectType)
            .insert(space);
        (id, format!("type:{name}"))
    };
    let member = |space: &mut AddressSpace, (parent, path): &(NodeId, String), name: &str, data: Option<DataTypeId>| {
        let id = nid(ns, &format!("{path}/{name}"));
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
    Types { step: step.0, transition: transition.0, action: action.0 }
}

/// The node layout (`docs/runtime.md`, "OPC UA"): `Objects/<POU>/{Inputs,Outputs,Locals,
/// Globals}/<variable>`, `Objects/<POU>/Chart/{Steps,Transitions,Actions}` and a chart per
/// SFC function block instance under `Chart`, `Objects/<POU>/Runtime`. A variable's node id is
/// its engineering name (`CarWash.StartButton`); every other node's id is its parent's id, `/`
/// and its browse name (`CarWash.StartButton/IecType`, `CarWash/Chart/Steps`), except the
/// steps, transitions and actions, which are `<POU>/Steps/<qualified name>` (and so on) wherever
/// their chart sits, and the charts of function block instances, `<POU>/Chart/<instance path>`.
/// `/` is in no IEC identifier, so no variable meets a node of the layout.
fn populate(hub: &Arc<Hub>, nodes: &Arc<InMemoryNodeManager<SfcNodes>>, ns: u16) {
    let info: &ChartInfo = &hub.info;
    let pou = info.pou.clone();
    let root = nid(ns, &pou);
    let mut table = Table::default();
    let space = nodes.address_space();
    let mut space = space.write();
    let program_type = nid(ns, "type:SfcProgramType");
    ObjectBuilder::new(&root, QualifiedName::new(ns, pou.as_str()), pou.as_str())
        .organized_by(ObjectId::ObjectsFolder)
        .has_type_definition(program_type)
        .insert(&mut *space);
    let folder = |space: &mut AddressSpace, id: &NodeId, name: &str, parent: &NodeId| {
        ObjectBuilder::new(id, QualifiedName::new(ns, name), name)
            .is_folder()
            .organized_by(parent.clone())
            .insert(space);
    };
    // A property of the node whose id is `parent` (the string `path`).
    let property =
        |space: &mut AddressSpace, (parent, path): (&NodeId, &str), name: &str, value: Variant, ty: DataTypeId| {
            let id = nid(ns, &format!("{path}/{name}"));
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
            let path = format!("{pou}.{}", var.name);
            let id = nid(ns, &path);
            let level = if section == Section::Output || !info.control {
                AccessLevel::CURRENT_READ
            } else {
                AccessLevel::CURRENT_READ | AccessLevel::CURRENT_WRITE
            };
            VariableBuilder::new(&id, QualifiedName::new(ns, var.name.as_str()), var.name.as_str())
                .organized_by(fid.clone())
                .has_type_definition(VariableTypeId::BaseDataVariableType)
                .data_type(ty.data_type())
                .access_level(level)
                .user_access_level(level)
                .minimum_sampling_interval(0.0)
                .insert(&mut *space);
            set_waiting(&mut space, &id);
            property(&mut space, (&id, &path), "IecType", Variant::from(var.ty.as_str()), DataTypeId::String);
            if let Some(at) = &var.location {
                property(&mut space, (&id, &path), "Address", Variant::from(at.as_str()), DataTypeId::String);
            }
            table.published.push((id.clone(), Source::Var(i, ty)));
            table.writable.insert(id, (i, ty, section));
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
    let chart_path = format!("{pou}/Chart");
    let chart = nid(ns, &chart_path);
    let own = charts.iter().any(|c| c.path.is_empty());
    let sfc_type = nid(ns, "type:SfcType");
    ObjectBuilder::new(&chart, QualifiedName::new(ns, "Chart"), "Chart")
        .component_of(root.clone())
        .has_type_definition(if own { sfc_type.clone() } else { ObjectTypeId::FolderType.into() })
        .insert(&mut *space);
    for (c, outline) in charts.iter().enumerate() {
        // The program's own chart is `Chart`; a function block instance's is `Chart/<path>`.
        let (cid, cpath) = if outline.path.is_empty() {
            (chart.clone(), chart_path.clone())
        } else {
            let p = format!("{chart_path}/{}", outline.path);
            let cid = nid(ns, &p);
            ObjectBuilder::new(&cid, QualifiedName::new(ns, outline.path.as_str()), outline.path.as_str())
                .organized_by(chart.clone())
                .has_type_definition(sfc_type.clone())
                .insert(&mut *space);
            property(&mut space, (&cid, &p), "FunctionBlock", Variant::from(outline.pou.as_str()), DataTypeId::String);
            (cid, p)
        };
        // Names inside a function block lose the instance prefix in browse names.
        let local = |q: &str| -> String {
            match q.strip_prefix(&outline.path).and_then(|r| r.strip_prefix('.')) {
                Some(r) if !outline.path.is_empty() => r.to_string(),
                _ => q.to_string(),
            }
        };
        let variable = |space: &mut AddressSpace, id: &NodeId, parent: &NodeId, name: &str, ty: DataTypeId| {
            VariableBuilder::new(id, QualifiedName::new(ns, name), name)
                .component_of(parent.clone())
                .has_type_definition(VariableTypeId::BaseDataVariableType)
                .data_type(ty)
                .access_level(AccessLevel::CURRENT_READ)
                .user_access_level(AccessLevel::CURRENT_READ)
                .minimum_sampling_interval(0.0)
                .insert(space);
            set_waiting(space, id);
        };
        let steps = nid(ns, &format!("{cpath}/Steps"));
        folder(&mut space, &steps, "Steps", &cid);
        for s in outline.steps.clone() {
            let Some((name, initial)) = info.steps.get(s as usize) else { continue };
            let bn = local(name);
            let spath = format!("{pou}/Steps/{name}");
            let sid = nid(ns, &spath);
            ObjectBuilder::new(&sid, QualifiedName::new(ns, bn.as_str()), bn.as_str())
                .organized_by(steps.clone())
                .has_type_definition(types.step.clone())
                .insert(&mut *space);
            property(&mut space, (&sid, &spath), "Initial", Variant::Boolean(*initial), DataTypeId::Boolean);
            let x = nid(ns, &format!("{spath}/X"));
            let t = nid(ns, &format!("{spath}/T"));
            variable(&mut space, &x, &sid, "X", DataTypeId::Boolean);
            variable(&mut space, &t, &sid, "T", DataTypeId::Duration);
            table.published.push((x, Source::StepX(s)));
            table.published.push((t, Source::StepT(s)));
        }
        let transitions = nid(ns, &format!("{cpath}/Transitions"));
        folder(&mut space, &transitions, "Transitions", &cid);
        for t in outline.transitions.clone() {
            let Some((name, from, to)) = info.transitions.get(t as usize) else { continue };
            let bn = local(name);
            let tpath = format!("{pou}/Transitions/{name}");
            let tid = nid(ns, &tpath);
            ObjectBuilder::new(&tid, QualifiedName::new(ns, bn.as_str()), bn.as_str())
                .organized_by(transitions.clone())
                .has_type_definition(types.transition.clone())
                .insert(&mut *space);
            let names =
                |l: &[u32]| -> Vec<UAString> { l.iter().map(|s| UAString::from(local(&info.step_name(*s)))).collect() };
            property(&mut space, (&tid, &tpath), "From", Variant::from(names(from)), DataTypeId::String);
            property(&mut space, (&tid, &tpath), "To", Variant::from(names(to)), DataTypeId::String);
            let g = nid(ns, &format!("{tpath}/Guard"));
            variable(&mut space, &g, &tid, "Guard", DataTypeId::Boolean);
            table.published.push((g, Source::Guard(t)));
        }
        let actions = nid(ns, &format!("{cpath}/Actions"));
        folder(&mut space, &actions, "Actions", &cid);
        for a in outline.actions.clone() {
            let Some((name, is_variable)) = info.actions.get(a as usize) else { continue };
            let bn = local(name);
            let apath = format!("{pou}/Actions/{name}");
            let aid = nid(ns, &apath);
            ObjectBuilder::new(&aid, QualifiedName::new(ns, bn.as_str()), bn.as_str())
                .organized_by(actions.clone())
                .has_type_definition(types.action.clone())
                .insert(&mut *space);
            let kind = if *is_variable { "variable" } else { "action" };
            property(&mut space, (&aid, &apath), "Kind", Variant::from(kind), DataTypeId::String);
            for (source, bn) in [(Source::ActionQ(a), "Q"), (Source::ActionA(a), "A")] {
                let id = nid(ns, &format!("{apath}/{bn}"));
                variable(&mut space, &id, &aid, bn, DataTypeId::Boolean);
                table.published.push((id, source));
            }
        }
        // Error records of supervision timeouts (issue 23): the last one's text, code and step,
        // and how many were made.
        for (bn, ty, node) in [
            ("LastError", DataTypeId::String, ErrorNode::Text),
            ("LastErrorCode", DataTypeId::Int32, ErrorNode::Code),
            ("LastErrorStep", DataTypeId::String, ErrorNode::Step),
            ("ErrorCount", DataTypeId::UInt64, ErrorNode::Count),
        ] {
            let id = nid(ns, &format!("{cpath}/{bn}"));
            variable(&mut space, &id, &cid, bn, ty);
            table.published.push((id, Source::Error(c, node)));
        }
    }
    // The runtime: state, scan count, jitter, and the methods.
    let rt_path = format!("{pou}/Runtime");
    let rt = nid(ns, &rt_path);
    ObjectBuilder::new(&rt, QualifiedName::new(ns, "Runtime"), "Runtime")
        .component_of(root.clone())
        .has_type_definition(ObjectTypeId::BaseObjectType)
        .insert(&mut *space);
    for (name, ty, node) in [
        ("State", DataTypeId::String, RuntimeNode::State),
        ("Halted", DataTypeId::Boolean, RuntimeNode::Halted),
        ("ScanCount", DataTypeId::UInt64, RuntimeNode::ScanCount),
        ("PeriodMs", DataTypeId::Duration, RuntimeNode::PeriodMs),
        ("JitterP50Us", DataTypeId::UInt64, RuntimeNode::JitterP50),
        ("JitterP99Us", DataTypeId::UInt64, RuntimeNode::JitterP99),
        ("JitterMaxUs", DataTypeId::UInt64, RuntimeNode::JitterMax),
        ("Overruns", DataTypeId::UInt64, RuntimeNode::Overruns),
    ] {
        let id = nid(ns, &format!("{rt_path}/{name}"));
        VariableBuilder::new(&id, QualifiedName::new(ns, name), name)
            .component_of(rt.clone())
            .has_type_definition(VariableTypeId::BaseDataVariableType)
            .data_type(ty)
            .access_level(AccessLevel::CURRENT_READ)
            .user_access_level(AccessLevel::CURRENT_READ)
            .minimum_sampling_interval(0.0)
            .insert(&mut *space);
        set_waiting(&mut space, &id);
        table.published.push((id, Source::Runtime(node)));
    }
    if info.control {
        for name in ["Halt", "Continue", "Reset"] {
            let id = nid(ns, &format!("{rt_path}/{name}"));
            MethodBuilder::new(&id, QualifiedName::new(ns, name), name)
                .component_of(rt.clone())
                .executable(true)
                .user_executable(true)
                .insert(&mut *space);
            table.methods.insert(id, name);
        }
    }
    drop(space);
    *nodes.inner().table.write().unwrap_or_else(|e| e.into_inner()) = table;
}

/// One reading of the run indexed by step, transition and action, so each node's value is one
/// lookup: a chart of thousands of steps costs its node count per state, not steps × active.
#[derive(Default)]
struct Lookup {
    /// Per step: its elapsed time when active.
    active: Vec<Option<i64>>,
    /// Per transition: its guard when evaluated (`Some(None)`: it faulted).
    guards: Vec<Option<Option<bool>>>,
    /// Per action: Q and A.
    actions: Vec<(bool, bool)>,
}

impl Lookup {
    fn fill(&mut self, info: &ChartInfo, st: &crate::board::ScanState) {
        self.active.clear();
        self.active.resize(info.steps.len(), None);
        for &(s, t) in &st.active {
            if let Some(slot) = self.active.get_mut(s as usize) {
                *slot = Some(t);
            }
        }
        self.guards.clear();
        self.guards.resize(info.transitions.len(), None);
        for &(t, g) in &st.guards {
            if let Some(slot) = self.guards.get_mut(t as usize) {
                *slot = Some(g);
            }
        }
        self.actions.clear();
        self.actions.resize(info.actions.len(), (false, false));
        for &(a, q, on) in &st.actions {
            if let Some(slot) = self.actions.get_mut(a as usize) {
                *slot = (q, on);
            }
        }
    }
}

/// The value (and a status other than Good) of a published node in one reading of the run
/// (`None`: not published yet).
fn value_of(info: &ChartInfo, image: &ImageView, at: &Lookup, source: Source) -> Option<(Variant, Option<StatusCode>)> {
    let digest = |f: fn(&crate::jitter::StatsDigest) -> u64| Variant::UInt64(image.digest.as_ref().map_or(0, f));
    let v = match source {
        Source::Runtime(node) => match node {
            RuntimeNode::State => Variant::from(image.state.name()),
            RuntimeNode::Halted => Variant::Boolean(image.halted),
            RuntimeNode::ScanCount => Variant::UInt64(image.scan_number()),
            RuntimeNode::PeriodMs => Variant::Double(info.period as f64 / 1000.0),
            RuntimeNode::JitterP50 => digest(|d| d.jitter[0]),
            RuntimeNode::JitterP99 => digest(|d| d.jitter[1]),
            RuntimeNode::JitterMax => digest(|d| d.jitter[2]),
            RuntimeNode::Overruns => digest(|d| d.overruns),
        },
        Source::Error(c, node) => {
            let e = image.errors.get(c);
            let last = e.and_then(|e| e.last.as_ref());
            match node {
                ErrorNode::Text => Variant::from(last.map(sfc_sim::ErrorRecord::message).unwrap_or_default()),
                ErrorNode::Code => {
                    let code = last.and_then(|r| r.code).unwrap_or(0);
                    Variant::Int32(code.clamp(i32::MIN.into(), i32::MAX.into()) as i32)
                }
                ErrorNode::Step => Variant::from(last.map(|r| r.step.clone()).unwrap_or_default()),
                ErrorNode::Count => Variant::UInt64(e.map_or(0, |e| e.count)),
            }
        }
        _ => {
            let st = image.scan.as_ref()?;
            match source {
                Source::Var(i, ty) => ty.variant(st.values.get(i)?),
                Source::StepX(s) => Variant::Boolean(at.active.get(s as usize).copied().flatten().is_some()),
                Source::StepT(s) => {
                    // An inactive step keeps the duration of its last activation (IEC 61131-3).
                    let us = match at.active.get(s as usize).copied().flatten() {
                        Some(t) => t,
                        None => st.times.get(s as usize).copied().unwrap_or(0),
                    };
                    Variant::Double(us as f64 / 1000.0)
                }
                Source::Guard(t) => match at.guards.get(t as usize).copied().flatten() {
                    Some(Some(b)) => Variant::Boolean(b),
                    // The guard faulted in this scan.
                    Some(None) => return Some((Variant::Empty, Some(StatusCode::BadInternalError))),
                    // Only the guards of enabled transitions (their steps active) are evaluated.
                    None => return Some((Variant::Empty, Some(StatusCode::GoodNoData))),
                },
                Source::ActionQ(a) => Variant::Boolean(at.actions.get(a as usize).is_some_and(|x| x.0)),
                Source::ActionA(a) => Variant::Boolean(at.actions.get(a as usize).is_some_and(|x| x.1)),
                Source::Runtime(_) | Source::Error(..) => return None,
            }
        }
    };
    Some((v, None))
}

/// Values carry a server timestamp and no source timestamp. async-opcua 0.19 holds back a
/// change that comes sooner than a monitored item's sampling interval after the one before it
/// (by their source timestamps) and releases it only with the item's next change, so a
/// subscriber would keep showing the first of two quick changes (an output that went TRUE and
/// back to FALSE would read TRUE until it changed again). A value without a source timestamp
/// is never held back: every change is reported, and the newest is always delivered.
fn published(v: Variant, status: Option<StatusCode>, now: async_opcua::types::DateTime) -> DataValue {
    DataValue { value: Some(v), status, server_timestamp: Some(now), ..Default::default() }
}

/// Brings the published nodes up to date with the board every `tick`: each reading of the run
/// ([`Hub::image`]) is set in one batch under the address space's lock, so a read or a
/// subscription never mixes two scans, and only the nodes whose value changed notify their
/// subscribers.
async fn follow(
    hub: Arc<Hub>,
    nodes: Arc<InMemoryNodeManager<SfcNodes>>,
    subscriptions: Arc<SubscriptionCache>,
    tick: std::time::Duration,
) {
    let published_nodes = std::mem::take(&mut nodes.inner().table.write().unwrap_or_else(|e| e.into_inner()).published);
    let mut last: Vec<Option<(Variant, Option<StatusCode>)>> = vec![None; published_nodes.len()];
    // The reading the last values were made from. The newest state and the error records are
    // compared by identity (each change is a new `Arc`); holding them keeps their memory from
    // being reused for another state in the meantime.
    let mut seen: Option<ImageView> = None;
    let mut lookup = Lookup::default();
    let mut every = tokio::time::interval(tick);
    every.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    while !hub.closing() {
        every.tick().await;
        let image = hub.image();
        let same = seen.as_ref().is_some_and(|s| {
            s.state_seq == image.state_seq
                && s.halted == image.halted
                && s.digest == image.digest
                && Arc::ptr_eq(&s.errors, &image.errors)
                && match (&s.scan, &image.scan) {
                    (Some(a), Some(b)) => Arc::ptr_eq(a, b),
                    (None, None) => true,
                    _ => false,
                }
        });
        if same {
            continue;
        }
        if let Some(st) = &image.scan {
            lookup.fill(&hub.info, st);
        }
        let now = async_opcua::types::DateTime::now();
        let mut changed: Vec<(&NodeId, Option<&async_opcua::types::NumericRange>, DataValue)> = Vec::new();
        for ((id, source), was) in published_nodes.iter().zip(last.iter_mut()) {
            let Some(value) = value_of(&hub.info, &image, &lookup, *source) else { continue };
            if was.as_ref() == Some(&value) {
                continue;
            }
            changed.push((id, None, published(value.0.clone(), value.1, now)));
            *was = Some(value);
        }
        if !changed.is_empty() {
            let _ = nodes.set_values(&subscriptions, changed.into_iter());
        }
        seen = Some(image);
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
    tokio::spawn(follow(hub.clone(), side.nodes.clone(), side.handle.subscriptions().clone(), side.tick));
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
