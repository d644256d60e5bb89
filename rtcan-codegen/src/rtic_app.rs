//! Each module's RTIC app as robot.toml lays it out: one async task per node placed on
//! the module, at the node's priority. `#[rtic::app]` needs literal tasks and
//! priorities, so the generator writes, per module, a `<module>_app!` macro (exported by
//! the node crate: Triskar2's build.rs, the `nodes` crate `rtcan new` writes) that feeds
//! the shared app skeleton (`rtcan_app_stm32f103::module_app!`, boards/app) the module's
//! node tasks, the dispatchers of their priority levels and the topics' ceilings. A
//! module's bin invokes it after naming its hardware; moving a node in robot.toml moves
//! its task to the other image with no change to node or bin code.
//!
//! Priorities (RTIC logical, boards/app `driver`): a node's task runs at the rank of its
//! robot.toml `priority` among the robot's distinct node priorities (1 = the lowest), so
//! robot.toml's order is kept, every module agrees, and the node band is as narrow as
//! the robot needs; the protocol task, the CAN interrupts and the slot timer sit above
//! the band (the skeleton asserts the band against `NODE_PRIORITY_LEVELS`).
use rtcan_model::Plan;

/// Free interrupts of the STM32F103 images RTIC may use as dispatchers of the node
/// tasks, one per priority level in use (EXTI1 is the protocol task's; the boards use no
/// EXTI line, the supervisor interrupts below are never enabled).
pub const DISPATCHERS: &[&str] = &[
    "EXTI2",
    "EXTI3",
    "EXTI4",
    "EXTI9_5",
    "EXTI15_10",
    "EXTI0",
    "TAMPER",
    "RTC",
    "FLASH",
    "RCC",
    "PVD",
    "WWDG",
];

/// Where the generated macros find the node tasks and the app skeleton.
#[derive(Clone, Copy, Debug)]
pub struct RticSpec<'a> {
    /// Absolute path of the node task modules from the image crate, e.g.
    /// `triskar2_nodes::tasks`: `<tasks>::<node>` has `new()` and
    /// `poll(&mut Task, now, &mut impl Hw) -> next due`.
    pub tasks: &'a str,
    /// Path of the skeleton macro, e.g. `rtcan_app_stm32f103::module_app`.
    pub skeleton: &'a str,
}

/// The RTIC priority of every node (indexed as `plan.nodes`): the rank of its
/// robot.toml priority among the robot's distinct node priorities, from 1.
pub fn node_priorities(plan: &Plan) -> Vec<u8> {
    let mut levels: Vec<u8> = plan.nodes.iter().map(|n| n.priority).collect();
    levels.sort_unstable();
    levels.dedup();
    plan.nodes
        .iter()
        .map(|n| {
            let rank = levels.iter().position(|&p| p == n.priority).unwrap_or(0) + 1;
            u8::try_from(rank).unwrap_or(u8::MAX)
        })
        .collect()
}

/// Ceiling of a topic's critical sections on one module.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ceiling {
    /// Only node tasks of the module use it: the highest of their priorities.
    Node(u8),
    /// It crosses the bus, so the protocol task (the engine's host) uses it too.
    Protocol,
}

/// Each topic a module's tasks touch (publisher or subscriber on it) with its ceiling
/// there, in robot.toml's topic order.
pub fn topic_ceilings(plan: &Plan, module: usize) -> Vec<(String, Ceiling)> {
    let prio = node_priorities(plan);
    let at = |n: usize| prio.get(n).copied().unwrap_or(1);
    let mut out = Vec::new();
    for t in &plan.topics {
        let mut local: Vec<u8> = t
            .subscribers
            .iter()
            .filter(|s| s.module == module)
            .map(|s| at(s.node))
            .collect();
        if t.module == module {
            local.push(at(t.publisher));
        }
        let Some(&highest) = local.iter().max() else {
            continue;
        };
        let ceiling = if t.on_bus {
            Ceiling::Protocol
        } else {
            Ceiling::Node(highest)
        };
        out.push((t.name.clone(), ceiling));
    }
    out
}

/// One node task of a module's app, as the skeleton takes it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NodeTask {
    /// Index into `plan.nodes`.
    pub node: usize,
    /// RTIC priority.
    pub priority: u8,
    /// Whether the engine's deliveries wake it (it subscribes to a topic published on
    /// another module and publishes no HRT topic: an HRT publisher runs on its slots).
    pub on_delivery: bool,
    /// Positions (in this list) of the local nodes subscribing to what it publishes
    /// (HRT publishers excepted): its task wakes theirs after each poll.
    pub wakes: Vec<usize>,
}

/// The node tasks of `module`, by ascending priority, then the poll order of the
/// module's app (publishers before their local subscribers): position 0, the
/// lowest-priority task, also logs the module's safe state.
pub fn node_tasks(plan: &Plan, module: usize) -> Vec<NodeTask> {
    let prio = node_priorities(plan);
    let at = |n: usize| prio.get(n).copied().unwrap_or(1);
    let mut order = crate::apps::poll_order(plan, module);
    // Stable: equal priorities keep the poll order.
    order.sort_by_key(|&n| at(n));
    // A node publishing an HRT topic is synchronous (R2P §3.4.5): its task runs on its
    // slots' clock and takes the latest samples when due, so neither deliveries nor local
    // publishers wake it (each wake-up would be a poll that finds nothing due, stealing
    // the lead time of the lower-priority HRT publishers it preempts).
    let synchronous = |n: usize| {
        plan.topics
            .iter()
            .any(|t| t.publisher == n && t.class == rtcan_core::Class::Hrt)
    };
    order
        .iter()
        .map(|&n| {
            let on_delivery = !synchronous(n)
                && plan
                    .topics
                    .iter()
                    .any(|t| t.module != module && t.subscribers.iter().any(|s| s.node == n));
            let wakes = order
                .iter()
                .enumerate()
                .filter(|&(_, &b)| {
                    b != n
                        && !synchronous(b)
                        && plan
                            .topics
                            .iter()
                            .any(|t| t.publisher == n && t.subscribers.iter().any(|s| s.node == b))
                })
                .map(|(i, _)| i)
                .collect();
            NodeTask {
                node: n,
                priority: at(n),
                on_delivery,
                wakes,
            }
        })
        .collect()
}

/// The `<module>_app!` macro of module `module` (source text).
pub fn rtic_app_macro(plan: &Plan, module: usize, spec: &RticSpec<'_>) -> String {
    let Some(m) = plan.modules.get(module) else {
        return String::new();
    };
    let tasks = node_tasks(plan, module);
    let mut levels: Vec<u8> = tasks.iter().map(|t| t.priority).collect();
    levels.dedup();
    let name = |n: usize| plan.nodes.get(n).map_or("", |x| x.name.as_str());
    let listed: Vec<String> = tasks
        .iter()
        .map(|t| {
            let robot_prio = plan.nodes.get(t.node).map_or(0, |x| x.priority);
            format!(
                "`{}` (robot.toml {robot_prio}, RTIC {})",
                name(t.node),
                t.priority
            )
        })
        .collect();
    let mut s = format!(
        "/// Module `{0}`'s RTIC app: {1}. Invoke it in the module's bin (see\n\
         /// `{2}!` for the names the bin provides).\n\
         #[macro_export]\nmacro_rules! {0}_app {{\n    () => {{\n        {2}! {{\n            dispatchers: [{3}],\n            nodes: [\n",
        m.name,
        if listed.is_empty() {
            "no node task".to_string()
        } else {
            format!("node tasks {}", listed.join(", "))
        },
        spec.skeleton,
        DISPATCHERS
            .iter()
            .take(levels.len())
            .copied()
            .collect::<Vec<_>>()
            .join(", "),
    );
    for (i, t) in tasks.iter().enumerate() {
        let wakes: Vec<String> = t.wakes.iter().map(|w| w.to_string()).collect();
        s.push_str(&format!(
            "                {{ index: {i}, name: node_{n}, priority: {p}, task: {tasks}::{n}, on_delivery: {d}, wakes: [{w}] }},\n",
            n = name(t.node),
            p = t.priority,
            tasks = spec.tasks,
            d = t.on_delivery,
            w = wakes.join(", "),
        ));
    }
    s.push_str("            ],\n            ceilings: [\n");
    for (topic, c) in topic_ceilings(plan, module) {
        let c = match c {
            Ceiling::Node(p) => p.to_string(),
            Ceiling::Protocol => "(fw::driver::PROTOCOL_PRIORITY)".to_string(),
        };
        s.push_str(&format!("                {topic} = {c},\n"));
    }
    s.push_str("            ],\n        }\n    };\n}\n");
    s
}

/// Every module's `<module>_app!` macro (source text), in bus-index order.
pub fn rtic_app_macros(plan: &Plan, spec: &RticSpec<'_>) -> String {
    let mut s = String::from(
        "// Each module's RTIC app (rtcan_codegen::rtic_app): one task per node, at its priority.\n",
    );
    for mi in 0..plan.modules.len() {
        s.push('\n');
        s.push_str(&rtic_app_macro(plan, mi, spec));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(src: &str) -> Plan {
        let a = rtcan_model::analyze("robot.toml", src);
        assert!(a.diagnostics.is_empty(), "{}", a.diagnostics.render());
        a.plan.unwrap()
    }

    /// Module a: `low` (1) publishes `t1` to `high` (9, local) and `far` (b); `mid` (5)
    /// subscribes to `t2` from `far`. Priorities 1, 5, 9 rank 1, 2, 3.
    const ROBOT: &str = r#"
[bus]
cycle = "10ms"
slots = 20
master = "a"

[types.V]
x = "f32"

[modules.a]
board = "stm32f103c8"

[modules.b]
board = "stm32f103c8"

[nodes.low]
module = "a"
priority = 1

[nodes.high]
module = "a"
priority = 9

[nodes.mid]
module = "a"
priority = 5

[nodes.far]
module = "b"
priority = 1

[topics.t1]
type = "V"
publisher = "low"
class = "nrt"
rate = "10Hz"
subscribers = ["high", "far"]

[topics.t2]
type = "V"
publisher = "far"
class = "nrt"
rate = "10Hz"
subscribers = ["mid"]

[topics.t3]
type = "V"
publisher = "mid"
class = "nrt"
rate = "10Hz"
subscribers = ["high"]
"#;

    const SPEC: RticSpec<'static> = RticSpec {
        tasks: "my_nodes::tasks",
        skeleton: "rtcan_app_stm32f103::module_app",
    };

    #[test]
    fn priorities_are_ranks_of_the_robot_toml_priorities() {
        let p = plan(ROBOT);
        let names: Vec<&str> = p.nodes.iter().map(|n| n.name.as_str()).collect();
        assert_eq!(names, ["low", "high", "mid", "far"]);
        assert_eq!(node_priorities(&p), [1, 3, 2, 1]);
    }

    #[test]
    fn ceilings_are_the_highest_local_accessor_or_the_protocol_task() {
        let p = plan(ROBOT);
        assert_eq!(
            topic_ceilings(&p, 0),
            [
                ("t1".to_string(), Ceiling::Protocol),
                ("t2".to_string(), Ceiling::Protocol),
                ("t3".to_string(), Ceiling::Node(3)),
            ]
        );
        assert_eq!(
            topic_ceilings(&p, 1),
            [
                ("t1".to_string(), Ceiling::Protocol),
                ("t2".to_string(), Ceiling::Protocol),
            ]
        );
    }

    #[test]
    fn the_app_macro_lists_each_node_task_at_its_priority() {
        let p = plan(ROBOT);
        assert_eq!(
            rtic_app_macro(&p, 0, &SPEC),
            "/// Module `a`'s RTIC app: node tasks `low` (robot.toml 1, RTIC 1), `mid` (robot.toml 5, RTIC 2), `high` (robot.toml 9, RTIC 3). Invoke it in the module's bin (see\n\
             /// `rtcan_app_stm32f103::module_app!` for the names the bin provides).\n\
             #[macro_export]\n\
             macro_rules! a_app {\n    () => {\n        rtcan_app_stm32f103::module_app! {\n            \
             dispatchers: [EXTI2, EXTI3, EXTI4],\n            nodes: [\n                \
             { index: 0, name: node_low, priority: 1, task: my_nodes::tasks::low, on_delivery: false, wakes: [2] },\n                \
             { index: 1, name: node_mid, priority: 2, task: my_nodes::tasks::mid, on_delivery: true, wakes: [2] },\n                \
             { index: 2, name: node_high, priority: 3, task: my_nodes::tasks::high, on_delivery: false, wakes: [] },\n            \
             ],\n            ceilings: [\n                \
             t1 = (fw::driver::PROTOCOL_PRIORITY),\n                \
             t2 = (fw::driver::PROTOCOL_PRIORITY),\n                \
             t3 = 3,\n            ],\n        }\n    };\n}\n"
        );
        let b = rtic_app_macro(&p, 1, &SPEC);
        assert!(b.contains("dispatchers: [EXTI2],\n"), "{b}");
        assert!(b.contains("{ index: 0, name: node_far, priority: 1, task: my_nodes::tasks::far, on_delivery: true, wakes: [] },\n"), "{b}");
        assert_eq!(rtic_app_macro(&p, 2, &SPEC), "", "no such module");
    }

    #[test]
    fn a_module_without_nodes_gets_an_app_without_node_tasks() {
        let src = format!("{ROBOT}\n[modules.c]\nboard = \"stm32f103c8\"\n");
        let p = plan(&src);
        let c = rtic_app_macro(&p, 2, &SPEC);
        assert!(
            c.starts_with("/// Module `c`'s RTIC app: no node task."),
            "{c}"
        );
        assert!(
            c.contains("dispatchers: [],\n            nodes: [\n            ],\n            ceilings: [\n            ],"),
            "{c}"
        );
    }
}
