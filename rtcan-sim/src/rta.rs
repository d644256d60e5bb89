//! Classical response-time analysis of fixed-priority CAN (Davis, Burns, Bril, Lukkien,
//! "Controller Area Network (CAN) schedulability analysis: Refuted, revisited and
//! revised", Real-Time Systems 35(3), 2007, eqs. 13-17): the bound the baseline (d)
//! must meet once its driver no longer inverts priorities.
use rtcan_core::Nanos;

/// One stream of frames: every frame of the stream has the same identifier priority.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Stream {
    /// Label.
    pub name: String,
    /// Arbitration key: the raw identifier (lower wins).
    pub key: u32,
    /// Worst-case transmission time of one frame, intermission included, ns.
    pub c_ns: Nanos,
    /// Minimum inter-arrival time, ns.
    pub t_ns: Nanos,
    /// Release jitter (queuing delay before the frame is in a mailbox), ns.
    pub j_ns: Nanos,
}

fn ceil_div(a: Nanos, b: Nanos) -> Nanos {
    a.div_ceil(b.max(1))
}

/// Worst-case response time of `streams[m]`, ns (release → end of frame); `None` when
/// the busy period does not end (utilisation of its level ≥ 1) or exceeds `limit_ns`.
pub fn response_time(
    streams: &[Stream],
    m: usize,
    bit_ns: Nanos,
    limit_ns: Nanos,
) -> Option<Nanos> {
    let sm = streams.get(m)?;
    let hp: Vec<&Stream> = streams.iter().filter(|s| s.key < sm.key).collect();
    // Blocking: one lower-priority frame that started just before the release.
    let b = streams
        .iter()
        .filter(|s| s.key > sm.key)
        .map(|s| s.c_ns)
        .max()
        .unwrap_or(0);
    // Length of the level-m busy period (eq. 16).
    let mut t = sm.c_ns;
    loop {
        let next = b + hp
            .iter()
            .chain(std::iter::once(&sm))
            .map(|s| ceil_div(t + s.j_ns, s.t_ns) * s.c_ns)
            .sum::<Nanos>();
        if next == t {
            break;
        }
        if next > limit_ns {
            return None;
        }
        t = next;
    }
    // Instances in the busy period (eq. 17), each one's queuing delay (eq. 14).
    let q_max = ceil_div(t + sm.j_ns, sm.t_ns);
    let mut worst = 0;
    for q in 0..q_max {
        let mut w = b + q * sm.c_ns;
        loop {
            let next = b
                + q * sm.c_ns
                + hp.iter()
                    .map(|s| ceil_div(w + s.j_ns + bit_ns, s.t_ns) * s.c_ns)
                    .sum::<Nanos>();
            if next == w {
                break;
            }
            if next > limit_ns {
                return None;
            }
            w = next;
        }
        // eq. 15: R(q) = J + w(q) − q·T + C.
        let r = (sm.j_ns + w + sm.c_ns).saturating_sub(q * sm.t_ns);
        worst = worst.max(r);
    }
    Some(worst)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(name: &str, key: u32, c: Nanos, t: Nanos) -> Stream {
        Stream {
            name: name.into(),
            key,
            c_ns: c,
            t_ns: t,
            j_ns: 0,
        }
    }

    /// Hand-checked: three streams, C = 135 µs each (8-byte worst case at 1 Mbit/s),
    /// periods 1, 5, 10 ms, τ_bit = 1 µs.
    #[test]
    fn matches_a_hand_computation() {
        let c = 135_000;
        let v = vec![
            s("a", 1, c, 1_000_000),
            s("b", 2, c, 5_000_000),
            s("c", 3, c, 10_000_000),
        ];
        // a: blocked by one lower frame, then sent: B + C.
        assert_eq!(response_time(&v, 0, 1_000, u64::MAX), Some(2 * c));
        // b: B + one a + C.
        assert_eq!(response_time(&v, 1, 1_000, u64::MAX), Some(3 * c));
        // c: no blocking (lowest), one a and one b.
        assert_eq!(response_time(&v, 2, 1_000, u64::MAX), Some(3 * c));
        // Overload: the busy period never ends.
        let over = vec![s("x", 1, 600, 1_000), s("y", 2, 600, 1_000)];
        assert_eq!(response_time(&over, 1, 1, 1_000_000_000), None);
    }
}
