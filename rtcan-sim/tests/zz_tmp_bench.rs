#![allow(clippy::unwrap_used)]
#[test]
#[ignore]
fn bench_exact_bits() {
    let f = rtcan_core::Frame::new(rtcan_core::CanId::from_raw(0x0123_4567).unwrap(), &[1, 2, 3, 4, 5, 6, 7, 8]).unwrap();
    let t = std::time::Instant::now();
    let mut s = 0u64;
    for i in 0..1_000_000u32 {
        let g = rtcan_core::Frame::new(rtcan_core::CanId::from_raw(i).unwrap(), f.data()).unwrap();
        s += u64::from(rtcan_core::timing::exact_bits(std::hint::black_box(&g)));
    }
    eprintln!("{s} {:?} per call", t.elapsed() / 1_000_000);
    let cfg = rtcan_sim::run::SimConfig { seconds: 10.0, record_wire: false, ..Default::default() };
    let sc = rtcan_sim::paper::scenario(rtcan_sim::paper::our_laxity(), 1.0);
    let r = rtcan_sim::run::run_engine(&sc, &cfg, rtcan_sim::policy::PolicyKind::Ours, rtcan_core::engine::Policy::OURS);
    eprintln!("{:?}", r.bus);
}
