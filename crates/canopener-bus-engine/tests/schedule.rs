//! The bus schedule on virtual time: arbitration, FIFO order, exact frame timing, driver lateness and
//! detaching, as scenarios and as properties over random submissions.

use std::time::Duration;

use canopener_bus_engine::{BusConfig, BusEngine, Delivery, Port};
use canopener_can::bits::frame_bits;
use canopener_can::{Bitrate, CanFrame, CanId, ExtendedId, Instant, StandardId};
use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;

fn std_frame(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::new(StandardId::new(id).unwrap(), data).unwrap()
}

fn us(micros: u64) -> Instant {
    Instant::from_micros(micros)
}

fn bus(bitrate: Bitrate) -> BusEngine {
    BusEngine::new(BusConfig { bitrate })
}

/// One frame handed to the bus at `at` by `port`.
#[derive(Debug, Clone, Copy)]
struct Submission {
    at: Instant,
    port: Port,
    frame: CanFrame,
}

/// A virtual-time driver that never oversleeps: it handles each deadline exactly when it falls due,
/// and hands over frames at their instants, before any deadline at the same instant (a frame that
/// becomes ready at an arbitration instant takes part in it).
fn drive_on_time(bus: &mut BusEngine, submissions: &[Submission]) -> Vec<Delivery> {
    let mut deliveries = Vec::new();
    let mut next = submissions.iter().peekable();
    loop {
        let deadline = bus.poll_timeout();
        match (next.peek(), deadline) {
            (Some(sub), Some(deadline)) if sub.at <= deadline => {
                bus.submit(sub.at, sub.port, sub.frame).unwrap();
                next.next();
            }
            (Some(sub), None) => {
                bus.submit(sub.at, sub.port, sub.frame).unwrap();
                next.next();
            }
            (_, Some(deadline)) => bus.handle_timeout(deadline),
            (None, None) => break,
        }
        deliveries.extend(std::iter::from_fn(|| bus.poll_delivery()));
    }
    deliveries
}

/// A driver that oversleeps: it hands over every frame at its instant but calls `handle_timeout`
/// only every `tick` (and once at the very end), far later than the deadlines.
fn drive_late(bus: &mut BusEngine, submissions: &[Submission], tick: Duration) -> Vec<Delivery> {
    let mut deliveries = Vec::new();
    let mut next_tick = Instant::ZERO + tick;
    for sub in submissions {
        while next_tick < sub.at {
            bus.handle_timeout(next_tick);
            next_tick += tick;
        }
        bus.submit(sub.at, sub.port, sub.frame).unwrap();
    }
    bus.handle_timeout(Instant::MAX);
    deliveries.extend(std::iter::from_fn(|| bus.poll_delivery()));
    deliveries
}

/// Handles every deadline on time until nothing is left to do.
fn run_until_idle(bus: &mut BusEngine) -> Vec<Delivery> {
    let mut deliveries = Vec::new();
    while let Some(deadline) = bus.poll_timeout() {
        bus.handle_timeout(deadline);
        deliveries.extend(std::iter::from_fn(|| bus.poll_delivery()));
    }
    deliveries
}

fn ids(deliveries: &[Delivery]) -> Vec<u32> {
    deliveries.iter().map(|d| d.frame.id().as_raw()).collect()
}

#[test]
fn lowest_id_wins_even_when_submitted_last_before_the_bus_went_idle() {
    let mut bus = bus(Bitrate::K500);
    let [a, b, c] = [bus.attach(), bus.attach(), bus.attach()];
    let busy = std_frame(0x700, &[1, 2, 3, 4, 5, 6, 7, 8]);
    let free_at = us(0) + Bitrate::K500.frame_duration(&busy);
    let subs = [
        Submission {
            at: us(0),
            port: a,
            frame: busy,
        },
        Submission {
            at: us(10),
            port: b,
            frame: std_frame(0x300, &[0xB]),
        },
        Submission {
            at: us(20),
            port: c,
            frame: std_frame(0x200, &[0xC]),
        },
        // Handed over last, one nanosecond before the bus goes idle: still wins.
        Submission {
            at: free_at - Duration::from_nanos(1),
            port: a,
            frame: std_frame(0x100, &[0xA]),
        },
    ];
    let deliveries = drive_on_time(&mut bus, &subs);
    assert_eq!(ids(&deliveries), vec![0x700, 0x100, 0x200, 0x300]);
    assert_eq!(deliveries[1].start, free_at);
    for pair in deliveries.windows(2) {
        let free = pair[0].start + Bitrate::K500.frame_duration(&pair[0].frame);
        assert_eq!(pair[1].start, free, "back to back after {:?}", pair[0].frame);
    }
    assert_eq!(
        [deliveries[1].from, deliveries[2].from, deliveries[3].from],
        [a, c, b]
    );
}

#[test]
fn a_frame_handed_over_exactly_when_the_bus_frees_takes_part_in_arbitration() {
    let mut bus = bus(Bitrate::M1);
    let [a, b] = [bus.attach(), bus.attach()];
    let first = std_frame(0x100, &[]);
    let free_at = us(0) + Bitrate::M1.frame_duration(&first);
    let subs = [
        Submission {
            at: us(0),
            port: a,
            frame: first,
        },
        Submission {
            at: us(1),
            port: a,
            frame: std_frame(0x600, &[]),
        },
        Submission {
            at: free_at,
            port: b,
            frame: std_frame(0x500, &[]),
        },
    ];
    assert_eq!(ids(&drive_on_time(&mut bus, &subs)), vec![0x100, 0x500, 0x600]);
}

#[test]
fn each_port_sends_in_fifo_order() {
    let mut bus = bus(Bitrate::K250);
    let [a, b] = [bus.attach(), bus.attach()];
    let subs = [
        Submission {
            at: us(0),
            port: a,
            frame: std_frame(0x700, &[]),
        },
        Submission {
            at: us(0),
            port: a,
            frame: std_frame(0x001, &[]),
        },
        Submission {
            at: us(0),
            port: b,
            frame: std_frame(0x400, &[]),
        },
        Submission {
            at: us(0),
            port: b,
            frame: std_frame(0x002, &[]),
        },
    ];
    // Only head frames contend: 0x400 beats 0x700; then 0x002 (b's new head) beats 0x700; 0x001 waits
    // behind 0x700 although it has the highest priority of all.
    assert_eq!(
        ids(&drive_on_time(&mut bus, &subs)),
        vec![0x400, 0x002, 0x700, 0x001]
    );
}

#[test]
fn standard_extended_and_remote_priorities() {
    let mut bus = bus(Bitrate::K125);
    let ports: Vec<Port> = (0..6).map(|_| bus.attach()).collect();
    let sid = StandardId::new(0x123).unwrap();
    let same_base = ExtendedId::new(0x123 << 18).unwrap();
    let lower_base = ExtendedId::new((0x122 << 18) | 0x3FFFF).unwrap();
    let frames = [
        CanFrame::remote(same_base, 0).unwrap(),
        CanFrame::new(same_base, &[]).unwrap(),
        CanFrame::remote(sid, 0).unwrap(),
        CanFrame::new(sid, &[]).unwrap(),
        CanFrame::new(lower_base, &[0xFF; 8]).unwrap(),
        CanFrame::new(ExtendedId::new(0x123 << 18 | 1).unwrap(), &[]).unwrap(),
    ];
    let subs: Vec<_> = frames
        .iter()
        .zip(&ports)
        .map(|(&frame, &port)| Submission {
            at: us(7),
            port,
            frame,
        })
        .collect();
    let order: Vec<CanFrame> = drive_on_time(&mut bus, &subs).iter().map(|d| d.frame).collect();
    // Smaller base id first; on equal base bits a standard frame (dominant IDE) beats any extended one
    // and a standard data frame its remote twin (RTR comes before IDE). In extended frames RTR is the
    // last arbitration bit, so the extension bits decide first: 048C0000#R beats 048C0001#.
    assert_eq!(
        order,
        vec![frames[4], frames[3], frames[2], frames[1], frames[0], frames[5]]
    );
}

#[test]
fn single_frame_timing_is_exact_at_each_cia_rate() {
    // The expedited download request of the reference is 121 bits long.
    let frame = std_frame(0x622, &[0x23, 0x04, 0x20, 0x00, 0x9C, 0xFF, 0xFF, 0xFF]);
    assert_eq!(frame_bits(&frame).total, 121);
    for (bitrate, bit_ns) in [
        (Bitrate::K125, 8_000),
        (Bitrate::K250, 4_000),
        (Bitrate::K500, 2_000),
        (Bitrate::M1, 1_000),
    ] {
        let mut bus = bus(bitrate);
        let [a, b] = [bus.attach(), bus.attach()];
        let t0 = Instant::from_millis(3);
        bus.submit(t0, a, frame).unwrap();
        assert_eq!(
            bus.poll_timeout(),
            Some(t0),
            "{bitrate}: an idle bus starts the frame at once"
        );
        bus.handle_timeout(t0);
        let at = t0 + Duration::from_nanos(118 * bit_ns);
        assert_eq!(bus.poll_timeout(), Some(at), "{bitrate}");
        bus.handle_timeout(at - Duration::from_nanos(1));
        assert_eq!(bus.poll_delivery(), None, "{bitrate}: not before the end of EOF");
        bus.handle_timeout(at);
        assert_eq!(
            bus.poll_delivery(),
            Some(Delivery {
                from: a,
                frame,
                start: t0,
                at
            }),
            "{bitrate}"
        );
        assert_eq!(bus.poll_timeout(), None, "{bitrate}: nothing left to do");

        // Handed over during the intermission: waits for the bus to be free.
        let free = t0 + Duration::from_nanos(121 * bit_ns);
        bus.submit(at + Duration::from_nanos(1), b, frame).unwrap();
        assert_eq!(bus.poll_timeout(), Some(free), "{bitrate}");
        assert_eq!(
            run_until_idle(&mut bus).first().map(|d| d.start),
            Some(free),
            "{bitrate}"
        );

        // Handed over after the bus went idle: starts at its own instant.
        let later = free + Duration::from_millis(5);
        bus.submit(later, a, frame).unwrap();
        assert_eq!(
            run_until_idle(&mut bus).first().map(|d| d.start),
            Some(later),
            "{bitrate}"
        );
        assert_eq!(bus.stats().frames, 3);
        assert_eq!(bus.stats().bits, 3 * 121);
        assert_eq!(bus.stats().busy, Duration::from_nanos(3 * 121 * bit_ns));
    }
}

#[test]
fn late_handle_timeout_gives_the_same_schedule() {
    let ports = 3;
    let mut subs = Vec::new();
    let mut bus_on_time = bus(Bitrate::K500);
    let port_list: Vec<Port> = (0..ports).map(|_| bus_on_time.attach()).collect();
    for i in 0..60u64 {
        let port = port_list[(i % ports) as usize];
        let id = 0x100 + ((i * 37) % 0x500) as u16;
        subs.push(Submission {
            at: us(i * 90),
            port,
            frame: std_frame(id, &[i as u8; 5]),
        });
    }
    let on_time = drive_on_time(&mut bus_on_time, &subs);
    for tick in [
        Duration::from_micros(333),
        Duration::from_millis(2),
        Duration::from_secs(1),
    ] {
        let mut late_bus = bus(Bitrate::K500);
        for _ in 0..ports {
            late_bus.attach();
        }
        assert_eq!(drive_late(&mut late_bus, &subs, tick), on_time, "tick {tick:?}");
        assert_eq!(late_bus.stats(), bus_on_time.stats());
    }
    assert_eq!(on_time.len(), 60);
}

#[test]
fn detach_drops_waiting_frames_but_finishes_the_one_on_the_wire() {
    let mut bus = bus(Bitrate::M1);
    let [a, b] = [bus.attach(), bus.attach()];
    bus.submit(us(0), a, std_frame(0x10, &[1])).unwrap();
    bus.submit(us(0), a, std_frame(0x11, &[2])).unwrap();
    bus.submit(us(0), a, std_frame(0x12, &[3])).unwrap();
    bus.submit(us(0), b, std_frame(0x20, &[4])).unwrap();
    bus.handle_timeout(us(0));
    assert_eq!(bus.pending(a), 2);
    bus.detach(a);
    assert_eq!(bus.pending(a), 0);
    assert_eq!(bus.ports().collect::<Vec<_>>(), vec![b]);
    let deliveries = run_until_idle(&mut bus);
    assert_eq!(ids(&deliveries), vec![0x10, 0x20]);
    assert_eq!(deliveries[0].from, a);
}

#[test]
fn odd_bitrates_do_not_drift() {
    // 333 333 bit/s: one bit is 3000.003 ns, so per-frame rounding would lose 1 ns every few frames.
    let bitrate = Bitrate::new(333_333).unwrap();
    let mut bus = bus(bitrate);
    let port = bus.attach();
    let frame = std_frame(0x181, &[0x5A; 8]);
    let bits = u64::from(frame_bits(&frame).total);
    let n_frames = 20_000u64;
    let mut submitted = 0;
    let mut now = Instant::ZERO;
    let mut last = None;
    while submitted < n_frames || bus.poll_timeout().is_some() {
        // Always one frame waiting, so the bus never idles between frames.
        if submitted < n_frames && bus.pending(port) == 0 {
            bus.submit(now, port, frame).unwrap();
            submitted += 1;
        }
        if let Some(deadline) = bus.poll_timeout() {
            now = deadline;
            bus.handle_timeout(now);
        }
        last = std::iter::from_fn(|| bus.poll_delivery()).last().or(last);
    }
    let last = last.unwrap();
    assert_eq!(bus.stats().frames, n_frames);
    // The last frame starts after exactly (n − 1) frames' worth of bits, rounded once.
    assert_eq!(
        last.start,
        Instant::ZERO + bitrate.bits_duration((n_frames - 1) * bits)
    );
    assert_eq!(
        last.at,
        Instant::ZERO + bitrate.bits_duration(n_frames * bits - 3)
    );
    assert_eq!(bus.stats().busy, bitrate.bits_duration(n_frames * bits));
}

/// What a correct schedule must satisfy, checked against a plain model of the per-port queues.
fn check_schedule(
    bitrate: Bitrate,
    subs: &[Submission],
    deliveries: &[Delivery],
) -> Result<(), TestCaseError> {
    prop_assert_eq!(deliveries.len(), subs.len(), "every frame is delivered once");
    let mut queues: std::collections::BTreeMap<Port, std::collections::VecDeque<Submission>> =
        Default::default();
    for sub in subs {
        queues.entry(sub.port).or_default().push_back(*sub);
    }
    let mut bus_free = Instant::ZERO;
    for delivery in deliveries {
        let duration = bitrate.frame_duration(&delivery.frame);
        let bits = u64::from(frame_bits(&delivery.frame).total);
        // Standard rates divide 10⁹, so per-frame durations are exact and may be compared directly.
        prop_assert_eq!(delivery.at, delivery.start + bitrate.bits_duration(bits - 3));
        let heads: Vec<Submission> = queues.values().filter_map(|q| q.front().copied()).collect();
        let earliest_ready = heads.iter().map(|s| s.at).min().unwrap();
        prop_assert_eq!(
            delivery.start,
            earliest_ready.max(bus_free),
            "starts as soon as bus and frame allow"
        );
        let own = queues
            .get_mut(&delivery.from)
            .and_then(|q| q.pop_front())
            .unwrap();
        prop_assert_eq!(own.frame, delivery.frame, "fifo within a port");
        prop_assert!(own.at <= delivery.start);
        for rival in heads
            .iter()
            .filter(|h| h.port != delivery.from && h.at <= delivery.start)
        {
            let key = (delivery.frame.arbitration_key(), delivery.from);
            prop_assert!(
                key < (rival.frame.arbitration_key(), rival.port),
                "{:?} lost to {:?}",
                rival,
                delivery
            );
        }
        prop_assert!(delivery.start >= bus_free, "no overlap");
        bus_free = delivery.start + duration;
    }
    Ok(())
}

fn any_frame() -> impl Strategy<Value = CanFrame> {
    let id = prop_oneof![
        3 => (0u16..=0x7FF).prop_map(|raw| CanId::Standard(StandardId::new(raw).unwrap())),
        1 => (0u32..=0x1FFF_FFFF).prop_map(|raw| CanId::Extended(ExtendedId::new(raw).unwrap())),
        // Few distinct ids so equal arbitration keys from different ports occur.
        1 => (0u16..4).prop_map(|raw| CanId::Standard(StandardId::new(raw).unwrap())),
    ];
    canopener_can::strategy::frame_with_id(id)
}

fn any_bitrate() -> impl Strategy<Value = Bitrate> {
    prop::sample::select(vec![
        Bitrate::K10,
        Bitrate::K125,
        Bitrate::K250,
        Bitrate::K500,
        Bitrate::K800,
        Bitrate::M1,
    ])
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 300,
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("proptest-regressions"))),
        ..ProptestConfig::default()
    })]

    #[test]
    fn random_submissions_make_a_valid_schedule(
        bitrate in any_bitrate(),
        raw in proptest::collection::vec((0usize..4, 0u64..400, any_frame()), 1..120),
        tick_us in 1u64..5_000,
    ) {
        let mut bus = bus(bitrate);
        let ports: Vec<Port> = (0..4).map(|_| bus.attach()).collect();
        // Gaps in units of 1 µs scaled to the bit time, so the bus is sometimes idle, sometimes saturated.
        let bit_ns = bitrate.bit_time().as_nanos() as u64;
        let mut t = 0;
        let subs: Vec<Submission> = raw.iter().map(|&(port, gap, frame)| {
            t += gap * bit_ns / 4;
            Submission { at: Instant::from_nanos(t), port: ports[port], frame }
        }).collect();
        let deliveries = drive_on_time(&mut bus, &subs);
        check_schedule(bitrate, &subs, &deliveries)?;

        let stats = bus.stats();
        let expected_busy: Duration = subs.iter().map(|s| bitrate.frame_duration(&s.frame)).sum();
        prop_assert_eq!(stats.busy, expected_busy);
        prop_assert_eq!(stats.frames, subs.len() as u64);
        prop_assert_eq!(stats.bits, subs.iter().map(|s| u64::from(frame_bits(&s.frame).total)).sum::<u64>());

        let mut late_bus = bus_with_ports(bitrate, 4);
        let late = drive_late(&mut late_bus, &subs, Duration::from_nanos(tick_us * bit_ns));
        prop_assert_eq!(late, deliveries, "oversleeping must not change the schedule");
    }
}

fn bus_with_ports(bitrate: Bitrate, n: usize) -> BusEngine {
    let mut bus = bus(bitrate);
    for _ in 0..n {
        bus.attach();
    }
    bus
}
