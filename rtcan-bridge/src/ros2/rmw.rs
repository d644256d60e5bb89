//! rmw_zenoh's names on Zenoh, as its docs/design.md describes them (ros2/rmw_zenoh,
//! design.md at commit 99a6a2bd10b949052f4f12c5854825dc005e95a5, rmw_zenoh on zenoh 1.x;
//! sections "Topic and Service name mapping to Zenoh key
//! expressions", "Graph Cache" and "Publishers"):
//! - data: `<domain_id>/<fully_qualified_name without the leading />/<type_name>/<type_hash>`;
//! - liveliness tokens: `@ros2_lv/<domain_id>/<session_id>/<node_id>/<entity_id>/<kind>/
//!   <mangled_enclave>/<mangled_namespace>/<node_name>[/<mangled_qualified_name>/<type_name>/
//!   <type_hash>/<qos>]`, a mangled name having each `/` replaced by `%`;
//! - each sample's attachment: sequence number (i64 LE), source timestamp (i64 LE, ns
//!   since the UNIX epoch), GID length (1 byte, 16), GID (16 bytes); the GID is the
//!   XXH3-128 of the entity's liveliness key expression, low 64 bits first, each half
//!   little-endian (rmw_zenoh_cpp/src/detail/liveliness_utils.cpp, `Entity::Entity`).

/// Prefix of every liveliness token.
pub const ADMIN_SPACE: &str = "@ros2_lv";

/// Kind of a graph entity.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `NN`.
    Node,
    /// `MP`.
    Publisher,
    /// `MS`.
    Subscription,
}

impl Kind {
    fn code(self) -> &'static str {
        match self {
            Kind::Node => "NN",
            Kind::Publisher => "MP",
            Kind::Subscription => "MS",
        }
    }
}

/// `/` → `%`.
pub fn mangle(name: &str) -> String {
    name.replace('/', "%")
}

/// The QoS field of a token for the default profile (reliable, volatile, keep last) with
/// history `depth`: only values that differ from rmw_zenoh's defaults are written, so
/// this is `::,<depth>:,:,:,,` (design.md's `listener` example: `::,10:,:,:,,`).
pub fn qos_default(depth: u32) -> String {
    format!("::,{depth}:,:,:,,")
}

/// A ROS 2 node as rmw_zenoh names it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NodeNames {
    /// `ROS_DOMAIN_ID`.
    pub domain: u32,
    /// Zenoh session ID as text.
    pub zid: String,
    /// Node ID within the session.
    pub node_id: u32,
    /// Namespace (`/` or `/ns`).
    pub namespace: String,
    /// Node name.
    pub name: String,
}

impl NodeNames {
    /// The fully qualified name of `topic` in this node's namespace.
    pub fn qualified(&self, topic: &str) -> String {
        if self.namespace == "/" {
            format!("/{topic}")
        } else {
            format!("{}/{topic}", self.namespace)
        }
    }

    /// The key expression samples of `topic` (type `dds`, hash `hash`) are put on.
    pub fn topic_key(&self, topic: &str, dds: &str, hash: &str) -> String {
        let q = self.qualified(topic);
        format!("{}/{}/{dds}/{hash}", self.domain, q.trim_start_matches('/'))
    }

    /// The node's liveliness token.
    pub fn node_token(&self) -> String {
        self.token(self.node_id, Kind::Node)
    }

    fn token(&self, id: u32, kind: Kind) -> String {
        format!(
            "{ADMIN_SPACE}/{}/{}/{}/{id}/{}/%/{}/{}",
            self.domain,
            self.zid,
            self.node_id,
            kind.code(),
            mangle(&self.namespace),
            mangle(&self.name)
        )
    }

    /// The liveliness token of publisher or subscription `id` on `topic`.
    pub fn entity_token(
        &self,
        id: u32,
        kind: Kind,
        topic: &str,
        dds: &str,
        hash: &str,
        qos: &str,
    ) -> String {
        format!(
            "{}/{}/{}/{}/{qos}",
            self.token(id, kind),
            mangle(&self.qualified(topic)),
            mangle(dds),
            mangle(hash)
        )
    }
}

/// The GID of the entity whose liveliness token is `token`.
pub fn gid(token: &str) -> [u8; 16] {
    xxhash_rust::xxh3::xxh3_128(token.as_bytes()).to_le_bytes()
}

/// The attachment of one sample.
pub fn attachment(seq: i64, timestamp_ns: i64, gid: &[u8; 16]) -> Vec<u8> {
    let mut a = Vec::with_capacity(33);
    a.extend_from_slice(&seq.to_le_bytes());
    a.extend_from_slice(&timestamp_ns.to_le_bytes());
    a.push(16);
    a.extend_from_slice(gid);
    a
}

/// An attachment read back: (sequence number, timestamp ns, GID).
pub fn parse_attachment(a: &[u8]) -> Option<(i64, i64, [u8; 16])> {
    if a.len() != 33 || a.get(16) != Some(&16) {
        return None;
    }
    let seq = i64::from_le_bytes(a.get(..8)?.try_into().ok()?);
    let ts = i64::from_le_bytes(a.get(8..16)?.try_into().ok()?);
    let gid: [u8; 16] = a.get(17..)?.try_into().ok()?;
    Some((seq, ts, gid))
}
