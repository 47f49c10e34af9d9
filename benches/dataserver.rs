//! DataServer benchmarks. Every figure is measured against a baseline in the same run, so
//! what matters is the ratio, not the absolute time (this is often a shared, noisy machine).
//!
//! | figure     | ours                                        | baseline                                   | target |
//! |------------|---------------------------------------------|--------------------------------------------|--------|
//! | latency    | write → subscriber callback → signal back   | crossbeam hop A → B → signal back          | ≤ 2×   |
//! | … busy     | the same with a spinning neighbour thread    | the same hop, same neighbour               | ≤ 2×   |
//! | … blocked  | the same on the default pool while another  | the same, nobody blocked                    | ≤ 1.2× |
//! |            | subscriber blocks 100 ms at a time          |                                            |        |
//! | fan-out    | one write reaching 16 subscribers           | one tokio broadcast send, 16 receivers     | ≤ 1.5× |
//! | isolation  | write, 100,000 subs on unrelated objects    | the same write, no subscriptions           | ≤ 1.1× |
//! | read       | `get(guid, name)`                           | std `HashMap` lookup + clone               | —      |
//! | scale      | 100k objects, 1M properties, 100k subs      | build time, resident memory, bytes/sub     | —      |
//!
//! Criterion measures the means (groups `latency`, `fanout`, `isolation`, `read`). Criterion
//! gives no percentiles, so the `percentiles` section times 20,000 single round trips with
//! `Instant` for ours and the baseline, interleaved in blocks so both see the same machine
//! noise, and prints median and p99. The `summary` section measures every per-operation
//! ratio the same interleaved way and prints one table (stderr). The `scale` section runs
//! once, first, in a fresh process (so RSS deltas are not hidden by memory freed earlier).
//!
//! `cargo bench --bench dataserver [-- FILTER]`: FILTER (a substring) also selects among the
//! `scale`, `percentiles` and `summary` sections. Under `cargo test --benches` (no `--bench`
//! flag) everything runs once, at a small size.

mod common;
mod dataserver_load;
use common::filter;
use criterion::{Criterion, criterion_group};
use crossbeam_channel::{Receiver, Sender};
use mocu_dataserver::{Config, DataServer, Guid, Kind, ObjectInfo, PropName, Topic, Value};
use std::collections::HashMap;
use std::hint::black_box;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Set when not run by `cargo bench` (test mode): every size shrinks so it runs in moments.
static QUICK: AtomicBool = AtomicBool::new(false);

fn quick() -> bool {
    QUICK.load(Ordering::Relaxed)
}

/// `full` under `cargo bench`, `small` in test mode.
fn size(full: usize, small: usize) -> usize {
    if quick() { small } else { full }
}

const FANOUT: usize = 16;

// ----- latency: write → callback → signal back, vs a bare crossbeam hop ------------------
//
// Both sides use exactly the same threads and wake-ups: the measuring thread starts the
// round trip, ONE other thread is woken through a crossbeam unbounded channel (the
// DataServer's worker pool is fed by one), and that thread signals back over another
// crossbeam unbounded channel on which the measuring thread blocks. The DataServer gets a
// single worker so the consumer side is one thread, as for the bare hop.

/// Ours: `set` on the measuring thread; the subscription's callback runs on the single
/// DataServer worker and signals back.
struct DsHop {
    ds: DataServer,
    obj: Guid,
    name: PropName,
    back: Receiver<()>,
    next: i64,
}

impl DsHop {
    fn new() -> DsHop {
        let ds = DataServer::new(Config { workers: 1 });
        let obj = ds.create_object(ds.root(), ObjectInfo::new("robot", "robot")).unwrap();
        let name = PropName::new("speed");
        ds.set(obj, name, Value::Int(0)).unwrap();
        let (tx, back) = crossbeam_channel::unbounded();
        ds.subscribe(Topic::property_names(obj, &["speed"]), move |n| {
            // The initial value arrives as `New`; only the benchmark's writes signal.
            if n.kind == Kind::Changed {
                black_box(n.value());
                tx.send(()).unwrap();
            }
        })
        .unwrap();
        ds.quiesce();
        DsHop { ds, obj, name, back, next: 0 }
    }

    fn round_trip(&mut self) {
        self.next += 1;
        self.ds.set(self.obj, self.name, Value::Int(self.next)).unwrap();
        self.back.recv().unwrap();
    }
}

/// Baseline: the same value sent to a thread over a crossbeam channel, which signals back.
struct BareHop {
    to_b: Option<Sender<Value>>,
    back: Receiver<()>,
    thread: Option<JoinHandle<()>>,
    next: i64,
}

impl BareHop {
    fn new() -> BareHop {
        let (to_b, rx) = crossbeam_channel::unbounded::<Value>();
        let (tx, back) = crossbeam_channel::unbounded();
        let thread = std::thread::spawn(move || {
            while let Ok(v) = rx.recv() {
                black_box(&v);
                tx.send(()).unwrap();
            }
        });
        BareHop { to_b: Some(to_b), back, thread: Some(thread), next: 0 }
    }

    fn round_trip(&mut self) {
        self.next += 1;
        self.to_b.as_ref().unwrap().send(Value::Int(self.next)).unwrap();
        self.back.recv().unwrap();
    }
}

impl Drop for BareHop {
    fn drop(&mut self) {
        self.to_b = None;
        if let Some(t) = self.thread.take() {
            t.join().unwrap();
        }
    }
}

fn bench_latency(c: &mut Criterion) {
    let mut g = c.benchmark_group("latency");
    // Set-ups are built on first use (criterion calls each closure once per sample), so
    // benchmarks a FILTER leaves out cost nothing.
    let (mut ours, mut bare) = (None, None);
    g.bench_function("dataserver_write_to_callback_round_trip", |b| {
        let ours = ours.get_or_insert_with(DsHop::new);
        b.iter(|| ours.round_trip())
    });
    g.bench_function("baseline_crossbeam_hop_round_trip", |b| {
        let bare = bare.get_or_insert_with(BareHop::new);
        b.iter(|| bare.round_trip())
    });
    g.finish();
}

// ----- fan-out: one write to 16 subscribers, vs one broadcast send to 16 receivers -------
//
// Both sides: the measuring thread arms a countdown of 16, makes ONE write (ours) or ONE
// `broadcast::Sender::send` (baseline), and blocks on a crossbeam channel. The 16 consumers
// all live on ONE consumer thread: the single DataServer worker running 16 subscription
// callbacks, or a tokio current-thread runtime on one thread running 16 tasks each awaiting
// its own `broadcast::Receiver`. Each consumer decrements the countdown; the last one
// signals back. So both wake one thread and run 16 deliveries on it. Cost per delivery is
// the round trip / 16.

struct DsFanout {
    ds: DataServer,
    obj: Guid,
    name: PropName,
    remaining: Arc<AtomicUsize>,
    back: Receiver<()>,
    next: i64,
}

impl DsFanout {
    fn new() -> DsFanout {
        let ds = DataServer::new(Config { workers: 1 });
        let obj = ds.create_object(ds.root(), ObjectInfo::new("robot", "robot")).unwrap();
        let name = PropName::new("speed");
        ds.set(obj, name, Value::Int(0)).unwrap();
        let remaining = Arc::new(AtomicUsize::new(0));
        let (tx, back) = crossbeam_channel::unbounded();
        for _ in 0..FANOUT {
            let tx = tx.clone();
            let remaining = remaining.clone();
            ds.subscribe(Topic::property_names(obj, &["speed"]), move |n| {
                if n.kind == Kind::Changed {
                    black_box(n.value());
                    if remaining.fetch_sub(1, Ordering::AcqRel) == 1 {
                        tx.send(()).unwrap();
                    }
                }
            })
            .unwrap();
        }
        ds.quiesce();
        DsFanout { ds, obj, name, remaining, back, next: 0 }
    }

    fn round_trip(&mut self) {
        self.next += 1;
        self.remaining.store(FANOUT, Ordering::Release);
        self.ds.set(self.obj, self.name, Value::Int(self.next)).unwrap();
        self.back.recv().unwrap();
    }
}

struct BroadcastFanout {
    tx: Option<tokio::sync::broadcast::Sender<Value>>,
    remaining: Arc<AtomicUsize>,
    back: Receiver<()>,
    thread: Option<JoinHandle<()>>,
    next: i64,
}

impl BroadcastFanout {
    fn new() -> BroadcastFanout {
        let (tx, _) = tokio::sync::broadcast::channel::<Value>(FANOUT);
        let receivers: Vec<_> = (0..FANOUT).map(|_| tx.subscribe()).collect();
        let remaining = Arc::new(AtomicUsize::new(0));
        let (back_tx, back) = crossbeam_channel::unbounded();
        let (ready_tx, ready) = crossbeam_channel::bounded(0);
        let rem = remaining.clone();
        let thread = std::thread::spawn(move || {
            let rt = tokio::runtime::Builder::new_current_thread().build().unwrap();
            rt.block_on(async move {
                let tasks: Vec<_> = receivers
                    .into_iter()
                    .map(|mut rx| {
                        let back = back_tx.clone();
                        let remaining = rem.clone();
                        tokio::spawn(async move {
                            while let Ok(v) = rx.recv().await {
                                black_box(&v);
                                if remaining.fetch_sub(1, Ordering::AcqRel) == 1 {
                                    back.send(()).unwrap();
                                }
                            }
                        })
                    })
                    .collect();
                // Let every task reach its first `recv` before the benchmark starts.
                tokio::task::yield_now().await;
                ready_tx.send(()).unwrap();
                for t in tasks {
                    t.await.unwrap();
                }
            });
        });
        ready.recv().unwrap();
        BroadcastFanout { tx: Some(tx), remaining, back, thread: Some(thread), next: 0 }
    }

    fn round_trip(&mut self) {
        self.next += 1;
        self.remaining.store(FANOUT, Ordering::Release);
        self.tx.as_ref().unwrap().send(Value::Int(self.next)).unwrap();
        self.back.recv().unwrap();
    }
}

impl Drop for BroadcastFanout {
    fn drop(&mut self) {
        self.tx = None;
        if let Some(t) = self.thread.take() {
            t.join().unwrap();
        }
    }
}

fn bench_fanout(c: &mut Criterion) {
    let mut g = c.benchmark_group("fanout");
    let (mut ours, mut base) = (None, None);
    // Criterion reports the time of one write reaching all 16; per delivery is that / 16.
    g.throughput(criterion::Throughput::Elements(FANOUT as u64));
    g.bench_function("dataserver_write_to_16_subscribers", |b| {
        let ours = ours.get_or_insert_with(DsFanout::new);
        b.iter(|| ours.round_trip())
    });
    g.bench_function("baseline_tokio_broadcast_to_16_receivers", |b| {
        let base = base.get_or_insert_with(BroadcastFanout::new);
        b.iter(|| base.round_trip())
    });
    g.finish();
}

// ----- isolation: a write is not slowed by subscriptions on other objects ----------------
//
// Two DataServers with the same shape: 100,000 unrelated objects (one property each) and a
// target object with no subscriber. In one, each unrelated object has one subscription
// (100,000 in all); in the other, none. Same write, same key, same value sequence.

struct IsoWorld {
    ds: DataServer,
    target: Guid,
    name: PropName,
    next: i64,
}

impl IsoWorld {
    fn new(unrelated: usize, subscribe: bool) -> IsoWorld {
        let ds = DataServer::default();
        let x = PropName::new("x");
        for i in 0..unrelated {
            let o =
                ds.create_object(ds.root(), ObjectInfo::new(&format!("o{i}"), "thing")).unwrap();
            ds.set(o, x, Value::Int(i as i64)).unwrap();
            if subscribe {
                ds.subscribe(Topic::properties(o), |n| {
                    black_box(n);
                })
                .unwrap();
            }
        }
        let target = ds.create_object(ds.root(), ObjectInfo::new("target", "robot")).unwrap();
        let name = PropName::new("speed");
        ds.set(target, name, Value::Int(0)).unwrap();
        ds.quiesce();
        assert_eq!(ds.subscription_count(), if subscribe { unrelated } else { 0 });
        IsoWorld { ds, target, name, next: 0 }
    }

    fn write(&mut self) {
        self.next += 1;
        self.ds.set(self.target, self.name, Value::Int(self.next)).unwrap();
    }
}

fn bench_isolation(c: &mut Criterion) {
    let mut g = c.benchmark_group("isolation");
    let n = size(100_000, 1_000);
    let (mut with, mut without) = (None, None);
    g.bench_function("write_with_100k_unrelated_subscriptions", |b| {
        let with = with.get_or_insert_with(|| IsoWorld::new(n, true));
        b.iter(|| with.write())
    });
    g.bench_function("baseline_write_with_no_subscriptions", |b| {
        let without = without.get_or_insert_with(|| IsoWorld::new(n, false));
        b.iter(|| without.write())
    });
    g.finish();
}

// ----- read: get(guid, name) vs a std HashMap --------------------------------------------
//
// The same 10,000 objects × 10 properties in the DataServer and in a std HashMap (default
// SipHash), read in the same pseudo-random key order, each read returning an owned Value.

struct ReadWorld {
    ds: DataServer,
    flat: HashMap<(Guid, PropName), Value>,
    nested: HashMap<Guid, HashMap<String, Value>>,
    keys: Vec<(Guid, PropName, &'static str)>,
    at: usize,
}

impl ReadWorld {
    fn new() -> ReadWorld {
        let objects = size(10_000, 100);
        let ds = DataServer::default();
        let names: Vec<PropName> = (0..10).map(|i| PropName::new(&format!("p{i}"))).collect();
        let mut flat = HashMap::new();
        let mut nested: HashMap<Guid, HashMap<String, Value>> = HashMap::new();
        let mut guids = Vec::new();
        for i in 0..objects {
            let o =
                ds.create_object(ds.root(), ObjectInfo::new(&format!("o{i}"), "thing")).unwrap();
            guids.push(o);
            for (j, &n) in names.iter().enumerate() {
                let v = Value::Int((i * 10 + j) as i64);
                ds.set(o, n, v.clone()).unwrap();
                flat.insert((o, n), v.clone());
                nested.entry(o).or_default().insert(n.as_str().to_string(), v);
            }
        }
        // xorshift: a fixed pseudo-random order that defeats the prefetcher equally for both.
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let keys = (0..4096)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                let o = guids[(s % objects as u64) as usize];
                let n = names[((s >> 32) % 10) as usize];
                (o, n, n.as_str())
            })
            .collect();
        ds.quiesce();
        ReadWorld { ds, flat, nested, keys, at: 0 }
    }

    fn key(&mut self) -> (Guid, PropName, &'static str) {
        self.at = (self.at + 1) & 4095;
        self.keys[self.at]
    }

    fn ds_get(&mut self) -> Value {
        let (g, n, _) = self.key();
        self.ds.get(g, n).unwrap()
    }

    fn ds_get_str(&mut self) -> Value {
        let (g, _, s) = self.key();
        self.ds.get(g, s).unwrap()
    }

    fn map_get(&mut self) -> Value {
        let (g, n, _) = self.key();
        self.flat.get(&(g, n)).cloned().unwrap()
    }

    fn nested_get_str(&mut self) -> Value {
        let (g, _, s) = self.key();
        self.nested.get(&g).and_then(|m| m.get(s)).cloned().unwrap()
    }
}

fn bench_read(c: &mut Criterion) {
    let mut g = c.benchmark_group("read");
    // One world for the four, built on first use.
    let mut w: Option<ReadWorld> = None;
    g.bench_function("dataserver_get_guid_propname", |b| {
        let w = w.get_or_insert_with(ReadWorld::new);
        b.iter(|| black_box(w.ds_get()))
    });
    g.bench_function("baseline_hashmap_guid_propname", |b| {
        let w = w.get_or_insert_with(ReadWorld::new);
        b.iter(|| black_box(w.map_get()))
    });
    g.bench_function("dataserver_get_guid_str", |b| {
        let w = w.get_or_insert_with(ReadWorld::new);
        b.iter(|| black_box(w.ds_get_str()))
    });
    g.bench_function("baseline_nested_hashmap_guid_str", |b| {
        let w = w.get_or_insert_with(ReadWorld::new);
        b.iter(|| black_box(w.nested_get_str()))
    });
    g.finish();
}

criterion_group! {
    name = groups;
    config = Criterion::default()
        .warm_up_time(Duration::from_millis(1000))
        .measurement_time(Duration::from_secs(3));
    targets = bench_latency, bench_fanout, bench_isolation, bench_read
}

// ----- scale: build time, resident memory, bytes per subscription ------------------------

/// Resident set size in bytes, from `/proc/self/statm` (pages) × the kernel page size.
fn rss_bytes() -> Option<u64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * page_size())
}

fn page_size() -> u64 {
    std::fs::read_to_string("/proc/self/smaps")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("KernelPageSize:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        })
        .map_or(4096, |kb| kb * 1024)
}

fn mib(b: i64) -> f64 {
    b as f64 / (1024.0 * 1024.0)
}

fn scale() {
    let objects = size(100_000, 1_000);
    let props_per_object = 10;
    let subs = objects;
    let Some(rss0) = rss_bytes() else {
        eprintln!("scale: /proc/self/statm unavailable; skipped");
        return;
    };
    let names: Vec<PropName> =
        (0..props_per_object).map(|i| PropName::new(&format!("q{i}"))).collect();
    let ds = DataServer::default();
    let rss_empty = rss_bytes().unwrap();

    let t = Instant::now();
    let mut guids = Vec::with_capacity(objects);
    for i in 0..objects {
        let parent = ds.root();
        guids.push(ds.create_object(parent, ObjectInfo::new(&format!("o{i}"), "thing")).unwrap());
    }
    let t_objects = t.elapsed();
    let rss_objects = rss_bytes().unwrap();

    let t = Instant::now();
    for (i, &o) in guids.iter().enumerate() {
        for (j, &n) in names.iter().enumerate() {
            let v = if j % 2 == 0 { Value::Int((i + j) as i64) } else { Value::Float(j as f64) };
            ds.set(o, n, v).unwrap();
        }
    }
    let t_props = t.elapsed();
    let rss_props = rss_bytes().unwrap();

    let delivered = Arc::new(AtomicUsize::new(0));
    let t = Instant::now();
    for &o in &guids {
        let d = delivered.clone();
        ds.subscribe(Topic::properties(o), move |_| {
            d.fetch_add(1, Ordering::Relaxed);
        })
        .unwrap();
    }
    let t_subscribe = t.elapsed();
    // The initial values (10 per subscription) are delivered on the workers.
    ds.quiesce();
    let t_subs_delivered = t.elapsed();
    let rss_subs = rss_bytes().unwrap();
    assert_eq!(delivered.load(Ordering::Relaxed), subs * props_per_object);
    assert_eq!(ds.subscription_count(), subs);

    let total_props = objects * props_per_object;
    let d_obj = rss_objects as i64 - rss_empty as i64;
    let d_props = rss_props as i64 - rss_objects as i64;
    let d_subs = rss_subs as i64 - rss_props as i64;
    eprintln!();
    eprintln!("== scale: {objects} objects, {total_props} properties, {subs} subscriptions ==");
    eprintln!(
        "  build objects        {:>9.1} ms   RSS +{:>7.1} MiB  ({:>5.0} B/object)",
        t_objects.as_secs_f64() * 1e3,
        mib(d_obj),
        d_obj as f64 / objects as f64
    );
    eprintln!(
        "  build properties     {:>9.1} ms   RSS +{:>7.1} MiB  ({:>5.0} B/property)",
        t_props.as_secs_f64() * 1e3,
        mib(d_props),
        d_props as f64 / total_props as f64
    );
    eprintln!(
        "  subscribe            {:>9.1} ms   RSS +{:>7.1} MiB  ({:>5.0} B/subscription)",
        t_subscribe.as_secs_f64() * 1e3,
        mib(d_subs),
        d_subs as f64 / subs as f64
    );
    eprintln!(
        "  ... + deliver {} initial values: {:.1} ms after the first subscribe",
        subs * props_per_object,
        t_subs_delivered.as_secs_f64() * 1e3
    );
    eprintln!(
        "  total build          {:>9.1} ms   RSS {:>7.1} MiB (process), +{:.1} MiB for the world",
        (t_objects + t_props + t_subs_delivered).as_secs_f64() * 1e3,
        mib(rss_subs as i64),
        mib(rss_subs as i64 - rss0 as i64)
    );
    drop(ds);
}

// ----- percentiles and the ratio summary (Instant-based, interleaved) --------------------

fn percentile(sorted: &[Duration], p: f64) -> Duration {
    let i = ((sorted.len() as f64 - 1.0) * p).round() as usize;
    sorted[i]
}

/// Times `n` single round trips of each, interleaved in blocks; returns the sorted samples.
fn round_trips(
    n: usize,
    mut ours: impl FnMut(),
    mut base: impl FnMut(),
) -> (Vec<Duration>, Vec<Duration>) {
    const BLOCK: usize = 500;
    for _ in 0..size(2_000, 20) {
        ours();
        base();
    }
    let mut o = Vec::with_capacity(n);
    let mut b = Vec::with_capacity(n);
    while o.len() < n {
        let k = BLOCK.min(n - o.len());
        for _ in 0..k {
            let t = Instant::now();
            ours();
            o.push(t.elapsed());
        }
        for _ in 0..k {
            let t = Instant::now();
            base();
            b.push(t.elapsed());
        }
    }
    o.sort();
    b.sort();
    (o, b)
}

fn us(d: Duration) -> f64 {
    d.as_secs_f64() * 1e6
}

fn percentiles(rows: &mut Vec<Row>) {
    let n = size(20_000, 200);
    let mut ours = DsHop::new();
    let mut bare = BareHop::new();
    let (o, b) = round_trips(n, || ours.round_trip(), || bare.round_trip());
    let (om, op) = (percentile(&o, 0.5), percentile(&o, 0.99));
    let (bm, bp) = (percentile(&b, 0.5), percentile(&b, 0.99));
    eprintln!();
    eprintln!("== percentiles: {n} round trips each, interleaved in blocks of 500 ==");
    eprintln!(
        "  latency  dataserver write→callback→signal   median {:>8.2} µs   p99 {:>8.2} µs",
        us(om),
        us(op)
    );
    eprintln!(
        "  latency  baseline crossbeam hop A→B→signal  median {:>8.2} µs   p99 {:>8.2} µs",
        us(bm),
        us(bp)
    );
    rows.push(Row::new("latency median (µs/round trip)", us(om), us(bm), Some(2.0)));
    rows.push(Row::new("latency p99 (µs/round trip)", us(op), us(bp), Some(2.0)));

    // The same, with a neighbour thread computing all the while (both sides).
    let spin = dataserver_load::Spinner::start();
    let (o, b) = round_trips(n, || ours.round_trip(), || bare.round_trip());
    drop(spin);
    let (om, op) = (percentile(&o, 0.5), percentile(&o, 0.99));
    let (bm, bp) = (percentile(&b, 0.5), percentile(&b, 0.99));
    eprintln!(
        "  busy neighbour: dataserver median {:>8.2} µs p99 {:>8.2} µs; crossbeam median {:>8.2} µs p99 {:>8.2} µs",
        us(om),
        us(op),
        us(bm),
        us(bp)
    );
    rows.push(Row::new("latency median, busy neighbour (µs)", us(om), us(bm), Some(2.0)));
    rows.push(Row::new("latency p99, busy neighbour (µs)", us(op), us(bp), Some(2.0)));

    // An unrelated subscriber while another blocks 100 ms at a time, vs none blocked
    // (both on the default pool).
    let mut blocked = dataserver_load::PoolHop::new(true);
    let mut free = dataserver_load::PoolHop::new(false);
    let n2 = size(5_000, 50);
    let (o, b) = round_trips(n2, || blocked.round_trip(), || free.round_trip());
    drop((blocked, free));
    let (om, op) = (percentile(&o, 0.5), percentile(&o, 0.99));
    let (bm, bp) = (percentile(&b, 0.5), percentile(&b, 0.99));
    eprintln!(
        "  blocked neighbour: median {:>8.2} µs p99 {:>8.2} µs; none blocked: median {:>8.2} µs p99 {:>8.2} µs",
        us(om),
        us(op),
        us(bm),
        us(bp)
    );
    rows.push(Row::new("latency median, a sub blocked 100 ms (µs)", us(om), us(bm), Some(1.2)));
    rows.push(Row::new("latency p99, a sub blocked 100 ms (µs)", us(op), us(bp), Some(1.2)));

    drop((ours, bare));
    let mut ours = DsFanout::new();
    let mut base = BroadcastFanout::new();
    let n = size(5_000, 50);
    let (o, b) = round_trips(n, || ours.round_trip(), || base.round_trip());
    let per = |d: Duration| us(d) / FANOUT as f64;
    eprintln!(
        "  fan-out  dataserver 1 write → 16 subs       median {:>8.2} µs   p99 {:>8.2} µs   ({:.3} µs/delivery)",
        us(percentile(&o, 0.5)),
        us(percentile(&o, 0.99)),
        per(percentile(&o, 0.5))
    );
    eprintln!(
        "  fan-out  tokio broadcast 1 send → 16 rx     median {:>8.2} µs   p99 {:>8.2} µs   ({:.3} µs/delivery)",
        us(percentile(&b, 0.5)),
        us(percentile(&b, 0.99)),
        per(percentile(&b, 0.5))
    );
    rows.push(Row::new(
        "fan-out median (µs/delivery, 16 subs)",
        per(percentile(&o, 0.5)),
        per(percentile(&b, 0.5)),
        Some(1.5),
    ));
}

/// Median per-operation time (ns) of ours and the baseline, timed in alternating batches.
fn interleaved(batch: u64, mut ours: impl FnMut(), mut base: impl FnMut()) -> (f64, f64) {
    let rounds = size(201, 3);
    let time = |f: &mut dyn FnMut()| {
        let t = Instant::now();
        for _ in 0..batch {
            f();
        }
        t.elapsed().as_secs_f64() * 1e9 / batch as f64
    };
    let _ = (time(&mut ours), time(&mut base));
    let mut o = Vec::new();
    let mut b = Vec::new();
    for _ in 0..rounds {
        o.push(time(&mut ours));
        b.push(time(&mut base));
    }
    o.sort_by(f64::total_cmp);
    b.sort_by(f64::total_cmp);
    (o[o.len() / 2], b[b.len() / 2])
}

fn summary(rows: &mut Vec<Row>) {
    let n = size(100_000, 1_000);
    let (mut with, mut without) = (IsoWorld::new(n, true), IsoWorld::new(n, false));
    let (o, b) = interleaved(2_000, || with.write(), || without.write());
    rows.push(Row::new("isolation: write, 100k unrelated subs (ns)", o, b, Some(1.1)));
    drop((with, without));

    let mut w = ReadWorld::new();
    let w = std::cell::RefCell::new(&mut w);
    let (o, b) = interleaved(
        4_000,
        || {
            black_box(w.borrow_mut().ds_get());
        },
        || {
            black_box(w.borrow_mut().map_get());
        },
    );
    rows.push(Row::new("read get(guid, PropName) vs HashMap (ns)", o, b, None));
    let (o, b) = interleaved(
        4_000,
        || {
            black_box(w.borrow_mut().ds_get_str());
        },
        || {
            black_box(w.borrow_mut().nested_get_str());
        },
    );
    rows.push(Row::new("read get(guid, &str) vs nested HashMap (ns)", o, b, None));
}

fn print_table(rows: &[Row]) {
    eprintln!();
    eprintln!("== summary (ours / baseline, measured in this run) ==");
    eprintln!(
        "  {:<44} {:>11} {:>11} {:>8} {:>8}  met?",
        "figure", "ours", "baseline", "ratio", "target"
    );
    for r in rows {
        let ratio = r.ours / r.base;
        let (target, met) = match r.target {
            Some(t) => (format!("≤{t}×"), if ratio <= t { "yes" } else { "NO" }),
            None => ("—".to_string(), "—"),
        };
        eprintln!(
            "  {:<44} {:>11.3} {:>11.3} {:>7.2}× {:>8}  {}",
            r.name, r.ours, r.base, ratio, target, met
        );
    }
}

struct Row {
    name: &'static str,
    ours: f64,
    base: f64,
    target: Option<f64>,
}

impl Row {
    fn new(name: &'static str, ours: f64, base: f64, target: Option<f64>) -> Row {
        Row { name, ours, base, target }
    }
}

fn main() {
    QUICK.store(!std::env::args().any(|a| a == "--bench"), Ordering::Relaxed);
    let filter = filter();
    let selected = |section: &str| filter.as_deref().is_none_or(|f| section.contains(f));
    if selected("scale") {
        scale();
    }
    groups();
    let mut rows = Vec::new();
    if selected("percentiles latency fanout") {
        percentiles(&mut rows);
    }
    if selected("summary isolation read") {
        summary(&mut rows);
    }
    if !rows.is_empty() {
        print_table(&rows);
    }
    Criterion::default().configure_from_args().final_summary();
}
