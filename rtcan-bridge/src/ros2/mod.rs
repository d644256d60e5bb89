//! `rtcan bridge --ros2`: the topics robot.toml maps to standard ROS 2 types (`ros2 =
//! "pkg/msg/Type"`) on Zenoh the way rmw_zenoh nodes put them (see [`rmw`] for the
//! version followed), so ROS 2 nodes on rmw_zenoh see them in `ros2 topic list` and
//! command the writable ones. The bridge is one ROS 2 node, `rtcan_bridge` in namespace
//! `/<robot>`; a mapped topic is published (`MP`) unless it is writable, then the node
//! subscribes to it (`MS`) and forwards what ROS 2 nodes publish onto the bus.
pub mod cdr;
pub mod rmw;
pub mod types;

use rtcan_host::Link;
use rtcan_model::bridge_keys::Ros2Type;
use rtcan_model::Plan;
use rtcan_sim::decode::{Catalog, Decoder};
use zenoh::handlers::FifoChannelHandler;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::sample::{Locality, Sample};
use zenoh::{Session, Wait};

use crate::Counts;
use rmw::{Kind, NodeNames};

/// The node name of every bridge.
pub const NODE_NAME: &str = "rtcan_bridge";
/// History depth in the tokens' QoS (rmw's default profile).
pub const DEPTH: u32 = 10;

/// One ROS 2 topic the bridge publishes.
struct Out {
    key: String,
    token_key: String,
    gid: [u8; 16],
    seq: i64,
    publisher: Publisher<'static>,
    _token: LivelinessToken,
}

/// Everything ROS 2 sees of one mapped robot topic.
struct Mapped {
    /// Catalog topic index.
    topic: usize,
    ty: Ros2Type,
    /// One per ROS 2 topic (`Range`: one per element).
    outs: Vec<Out>,
    range_max_m: f32,
}

/// A writable topic ROS 2 nodes command.
struct In {
    name: String,
    key: String,
    ty: Ros2Type,
    token_key: String,
    _token: LivelinessToken,
}

/// The bridge's ROS 2 entities on one session.
pub struct Ros2Bridge<'c> {
    session: Session,
    node: NodeNames,
    cat: &'c Catalog,
    dec: Decoder<'c>,
    mapped: Vec<Mapped>,
    ins: Vec<In>,
    _node_token: LivelinessToken,
    commands: Subscriber<FifoChannelHandler<Sample>>,
    /// Counts so far.
    pub counts: Counts,
    /// The last refusal or bad command, for the report.
    pub last_error: Option<String>,
}

/// ns since the UNIX epoch, now.
pub fn now_ns() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| i64::try_from(d.as_nanos()).unwrap_or(i64::MAX))
}

/// The ROS 2 topic names of robot topic `name` mapped to `ty` with `n` elements.
pub fn ros_topics(name: &str, ty: Ros2Type, elements: usize) -> Vec<String> {
    if ty == Ros2Type::Range && elements > 1 {
        (0..elements).map(|i| format!("{name}_{i}")).collect()
    } else {
        vec![name.to_string()]
    }
}

impl<'c> Ros2Bridge<'c> {
    /// Declares the node, a publisher and its token for every mapped topic (a
    /// subscription for the writable ones) on `session`.
    pub fn new(
        session: Session,
        plan: &Plan,
        cat: &'c Catalog,
        robot: &str,
        domain: u32,
        writable: &[String],
    ) -> Result<Self, String> {
        let node = NodeNames {
            domain,
            zid: session.zid().to_string(),
            node_id: 0,
            namespace: format!("/{robot}"),
            name: NODE_NAME.to_string(),
        };
        let zerr = |what: &str, e: zenoh::Error| format!("{what}: {e}");
        let live = |k: &str| {
            session
                .liveliness()
                .declare_token(k.to_string())
                .wait()
                .map_err(|e| zerr(&format!("liveliness token {k}"), e))
        };
        let node_token = live(&node.node_token())?;
        let mut mapped = Vec::new();
        let mut ins = Vec::new();
        let mut entity = 0u32;
        for tb in &plan.bridge.topics {
            let Some(ty) = tb.ros2 else { continue };
            let Some(index) = cat.topics.iter().position(|t| t.name == tb.name) else {
                continue; // not on the bus: nothing to bridge
            };
            let d = types::description(ty);
            let (dds, hash) = (types::dds_name(d.name), types::type_hash(&d));
            let qos = rmw::qos_default(DEPTH);
            if writable.contains(&tb.name) {
                entity += 1;
                let token_key =
                    node.entity_token(entity, Kind::Subscription, &tb.name, &dds, &hash, &qos);
                ins.push(In {
                    name: tb.name.clone(),
                    key: node.topic_key(&tb.name, &dds, &hash),
                    ty,
                    _token: live(&token_key)?,
                    token_key,
                });
                continue;
            }
            let (elements, range_max_m) = range_field(plan, &tb.name);
            let mut outs = Vec::new();
            for rt in ros_topics(&tb.name, ty, elements) {
                entity += 1;
                let token_key = node.entity_token(entity, Kind::Publisher, &rt, &dds, &hash, &qos);
                let key = node.topic_key(&rt, &dds, &hash);
                let publisher = session
                    .declare_publisher(key.clone())
                    .wait()
                    .map_err(|e| zerr(&format!("publisher {key}"), e))?;
                outs.push(Out {
                    gid: rmw::gid(&token_key),
                    _token: live(&token_key)?,
                    token_key,
                    key,
                    seq: 1,
                    publisher,
                });
            }
            mapped.push(Mapped {
                topic: index,
                ty,
                outs,
                range_max_m,
            });
        }
        // Every remote sample under the robot's namespace: the writable topics' are
        // commands, the rest refused and counted.
        let commands = session
            .declare_subscriber(format!("{domain}/{robot}/**"))
            .allowed_origin(Locality::Remote)
            .wait()
            .map_err(|e| zerr("command subscriber", e))?;
        Ok(Ros2Bridge {
            session,
            node,
            cat,
            dec: Decoder::new(cat),
            mapped,
            ins,
            _node_token: node_token,
            commands,
            counts: Counts::default(),
            last_error: None,
        })
    }

    /// The node's names (domain, session, namespace).
    pub fn node(&self) -> &NodeNames {
        &self.node
    }

    /// Every liveliness token the bridge holds: the node's first.
    pub fn tokens(&self) -> Vec<String> {
        let mut v = vec![self.node.node_token()];
        v.extend(self.ins.iter().map(|i| i.token_key.clone()));
        for m in &self.mapped {
            v.extend(m.outs.iter().map(|o| o.token_key.clone()));
        }
        v
    }

    /// Every data key the bridge publishes on.
    pub fn publish_keys(&self) -> Vec<String> {
        self.mapped
            .iter()
            .flat_map(|m| m.outs.iter().map(|o| o.key.clone()))
            .collect()
    }

    /// The session (for a test or bench to share).
    pub fn session(&self) -> &Session {
        &self.session
    }

    fn command(&mut self, s: &Sample, link: &mut dyn Link) {
        let k = s.key_expr().as_str();
        let Some(i) = self.ins.iter().find(|i| i.key == k) else {
            self.counts.refused += 1;
            self.last_error = Some(format!("refused a sample on `{k}`: not a writable topic"));
            return;
        };
        let (name, ty) = (i.name.clone(), i.ty);
        let r = match ty {
            Ros2Type::Twist => types::decode_twist(&s.payload().to_bytes()),
            other => Err(format!("{} is not taken from ROS 2", other.name())),
        };
        let r = r.and_then(|v| {
            let t = self
                .cat
                .topics
                .iter()
                .find(|t| t.name == name)
                .ok_or_else(|| format!("`{name}` is not on the bus"))?;
            let p = rtcan_host::value::from_json(t, &v)?;
            link.publish(&name, &p)
        });
        match r {
            Ok(()) => self.counts.accepted += 1,
            Err(e) => {
                self.counts.bad += 1;
                self.last_error = Some(format!("command on `{k}`: {e}"));
            }
        }
    }

    /// Takes the pending commands, then forwards one batch of the bus; `false` when the
    /// bus ended.
    pub fn step(&mut self, link: &mut dyn Link) -> Result<bool, String> {
        while let Ok(Some(s)) = self.commands.try_recv() {
            self.command(&s, link);
        }
        let Some(batch) = link.recv()? else {
            return Ok(false);
        };
        for (topic, payload) in crate::messages(&mut self.dec, batch) {
            self.put(topic, &payload)?;
        }
        Ok(true)
    }

    /// Puts one message of catalog topic `topic` on its ROS 2 topics (if mapped).
    pub fn put(&mut self, topic: usize, payload: &[u8]) -> Result<(), String> {
        let Some(t) = self.cat.topics.get(topic) else {
            return Ok(());
        };
        let Some(m) = self.mapped.iter_mut().find(|m| m.topic == topic) else {
            return Ok(());
        };
        let v = rtcan_host::value::to_json(t, payload);
        let now = now_ns();
        let msgs = types::encode(m.ty, &v, types::Stamp::from_ns(now), &t.name, m.range_max_m);
        for (o, cdr) in m.outs.iter_mut().zip(msgs) {
            o.publisher
                .put(cdr)
                .attachment(rmw::attachment(o.seq, now, &o.gid))
                .wait()
                .map_err(|e| format!("zenoh put {}: {e}", o.key))?;
            o.seq += 1;
            self.counts.published += 1;
        }
        Ok(())
    }
}

/// Elements of a topic's `range_mm` field and the largest range it holds, m.
fn range_field(plan: &Plan, topic: &str) -> (usize, f32) {
    let Some(t) = plan.topics.iter().find(|t| t.name == topic) else {
        return (1, 0.0);
    };
    let Some(f) = plan
        .types
        .get(t.ty)
        .and_then(|ty| ty.fields.iter().find(|f| f.name == "range_mm"))
    else {
        return (1, 0.0);
    };
    use rtcan_model::Prim;
    let max_mm: f64 = match f.ty.prim {
        Prim::U8 => 255.0,
        Prim::U16 => 65_535.0,
        Prim::I8 => 127.0,
        Prim::I16 => 32_767.0,
        Prim::U32 => 4_294_967_295.0,
        Prim::I32 => 2_147_483_647.0,
        _ => f64::from(f32::MAX),
    };
    (usize::from(f.ty.len.unwrap_or(1)), (max_mm / 1000.0) as f32)
}
