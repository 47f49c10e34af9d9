use super::*;

fn rtp_from(ssrc: u32, seq: u16, ts: u32, pt: u8, marker: bool, payload: &[u8]) -> Vec<u8> {
    let mut d = vec![0x80, pt | if marker { 0x80 } else { 0 }];
    d.extend_from_slice(&seq.to_be_bytes());
    d.extend_from_slice(&ts.to_be_bytes());
    d.extend_from_slice(&ssrc.to_be_bytes());
    d.extend_from_slice(payload);
    d
}

fn rtp(seq: u16, pt: u8, marker: bool, payload: &[u8]) -> Vec<u8> {
    rtp_from(9, seq, 1, pt, marker, payload)
}

/// SPS + PPS in a STAP-A, then a P slice: one H.264 unit per timestamp.
const SPS: [u8; 9] = [0x78, 0, 2, 0x67, 1, 0, 2, 0x68, 2];

fn feed(s: &mut Stream, from: &str, ds: &[Vec<u8>], t: Instant) -> Vec<Codec> {
    let mut out = Vec::new();
    for d in ds {
        s.datagram(from.parse().unwrap(), d, t, &mut |c, _| out.push(c));
    }
    out
}

/// An H.264 stream of `n` one-packet units (the first with parameter sets) from `seq0`.
fn h264_units(ssrc: u32, seq0: u16, n: u16) -> Vec<Vec<u8>> {
    (0..n)
        .map(|i| {
            let pl: &[u8] = if i == 0 { &SPS } else { &[0x41, 1] };
            rtp_from(ssrc, seq0.wrapping_add(i), 1000 + i as u32 * 3000, 96, true, pl)
        })
        .collect()
}

#[test]
fn h264_is_locked_after_two_packets_in_sequence() {
    let mut s = Stream::new();
    let t = Instant::now();
    let ps = vec![rtp(1, 96, true, &SPS), rtp(2, 96, true, &SPS), rtp(3, 96, true, &[0x41, 1])];
    let got = feed(&mut s, "127.0.0.1:9", &ps, t);
    assert_eq!(s.transport(), "rtp/h264");
    assert_eq!(got, vec![Codec::H264, Codec::H264, Codec::H264], "the candidate's too");
}

#[test]
fn raw_mjpeg_is_told_by_its_soi_and_rtp_jpeg_by_its_payload_type() {
    let mut s = Stream::new();
    let t = Instant::now();
    feed(&mut s, "127.0.0.1:9", &[vec![0xff, 0xd8, 0xff, 0xe0, 0, 2]], t);
    assert_eq!(s.transport(), "mjpeg");
    let mut s = Stream::new();
    let jh = [0, 0, 0, 0, 1, 50, 2, 2, 1, 2];
    feed(&mut s, "127.0.0.1:9", &[rtp(7, 26, true, &jh), rtp(8, 26, true, &jh)], t);
    assert_eq!(s.transport(), "rtp/jpeg");
}

#[test]
fn a_second_sender_is_ignored_until_the_first_is_silent() {
    let mut s = Stream::new();
    let t = Instant::now();
    let soi = vec![0xff, 0xd8, 0xff, 0xe0, 0, 2];
    feed(&mut s, "127.0.0.1:9", std::slice::from_ref(&soi), t);
    feed(&mut s, "127.0.0.1:10", std::slice::from_ref(&soi), t);
    assert_eq!(s.ignored, 1);
    let later = t + SILENCE;
    let sps = [0x78, 0, 2, 0x67, 1];
    feed(&mut s, "127.0.0.1:10", &[rtp(1, 97, false, &sps), rtp(2, 97, false, &sps)], later);
    assert_eq!(s.transport(), "rtp/h264");
    assert_eq!(s.sender(), Some("127.0.0.1:10".parse().unwrap()));
}

#[test]
fn a_squatter_sending_noise_never_holds_the_port() {
    let mut s = Stream::new();
    let t = Instant::now();
    let squat = vec![0x17u8; 24];
    let real = h264_units(5, 100, 20);
    let mut shown = 0;
    for (i, p) in real.iter().enumerate() {
        // The squatter sends first, and between every packet of the real stream.
        let at = t + Duration::from_millis(i as u64 * 33);
        s.datagram("10.0.0.66:4000".parse().unwrap(), &squat, at, &mut |_, _| {});
        s.datagram("10.0.0.7:5000".parse().unwrap(), p, at, &mut |_, _| shown += 1);
    }
    assert_eq!(s.sender(), Some("10.0.0.7:5000".parse().unwrap()));
    assert_eq!(shown, 20, "every unit");
    assert_eq!(s.stats().ignored, 20);
}

#[test]
fn interleaved_plausible_senders_do_not_keep_each_other_out() {
    let mut s = Stream::new();
    let t = Instant::now();
    let (a, b) = (h264_units(1, 10, 4), h264_units(2, 5000, 4));
    for (pa, pb) in a.iter().zip(&b) {
        s.datagram("10.0.0.1:1".parse().unwrap(), pa, t, &mut |_, _| {});
        s.datagram("10.0.0.2:1".parse().unwrap(), pb, t, &mut |_, _| {});
    }
    assert_eq!(s.sender(), Some("10.0.0.1:1".parse().unwrap()), "the first valid one");
    assert_eq!(s.stats().ignored, 3, "b's three packets after a was chosen");
}

#[test]
fn a_configured_source_or_ssrc_is_the_only_one_chosen() {
    let t = Instant::now();
    let cfg =
        StreamConfig { source: SourceFilter::parse("10.0.0.2").unwrap(), ..Default::default() };
    let mut s = Stream::with_config(cfg);
    feed(&mut s, "10.0.0.1:7", &h264_units(1, 1, 3), t);
    feed(&mut s, "10.0.0.2:7", &h264_units(2, 1, 3), t);
    assert_eq!(s.sender(), Some("10.0.0.2:7".parse().unwrap()));
    assert_eq!(s.stats().ignored, 3);
    let mut s = Stream::with_config(StreamConfig { ssrc: Some(2), ..Default::default() });
    feed(&mut s, "10.0.0.1:7", &h264_units(1, 1, 3), t);
    feed(&mut s, "10.0.0.1:7", &[vec![0xff, 0xd8, 0xff, 0xe0, 0, 2]], t);
    assert_eq!(s.transport(), "", "neither SSRC 1 nor MJPEG");
    feed(&mut s, "10.0.0.1:7", &h264_units(2, 1, 3), t);
    assert_eq!(s.transport(), "rtp/h264");
    assert_eq!(SourceFilter::parse("nonsense"), None);
}

#[test]
fn the_chosen_stream_gives_way_after_its_configured_silence() {
    let silence = Duration::from_millis(500);
    let mut s = Stream::with_config(StreamConfig { silence, ..Default::default() });
    let clock = mocu_dataserver::ManualClock::new();
    use mocu_dataserver::Clock;
    feed(&mut s, "10.0.0.1:7", &h264_units(1, 1, 3), clock.now());
    clock.advance(silence - Duration::from_millis(1));
    feed(&mut s, "10.0.0.2:7", &h264_units(2, 1, 3), clock.now());
    assert_eq!(s.sender(), Some("10.0.0.1:7".parse().unwrap()), "not silent long enough");
    clock.advance(Duration::from_millis(1));
    feed(&mut s, "10.0.0.2:7", &h264_units(2, 1, 3), clock.now());
    assert_eq!(s.sender(), Some("10.0.0.2:7".parse().unwrap()));
    assert_eq!(s.stats().ignored, 3);
}

#[test]
fn a_restart_with_the_same_ssrc_is_counted_and_decoding_goes_on() {
    let mut s = Stream::new();
    let t = Instant::now();
    let mut units = feed(&mut s, "10.0.0.1:7", &h264_units(3, 100, 10), t).len();
    units += feed(&mut s, "10.0.0.1:7", &h264_units(3, 30000, 10), t).len();
    let st = s.stats();
    assert_eq!(st.reorder.restarts, 1);
    assert_eq!(units, 20);
    assert_eq!((st.sent, st.units, st.dropped), (20, 20, 0));
}

#[test]
fn reordered_packets_are_put_back_in_order() {
    let mut s = Stream::new();
    let t = Instant::now();
    let mut ps = h264_units(3, 65530, 12); // wraps
    ps.swap(4, 5);
    ps.swap(8, 10);
    let units = feed(&mut s, "10.0.0.1:7", &ps, t).len();
    let st = s.stats();
    assert_eq!((units, st.dropped, st.lost_packets), (12, 0, 0));
    assert_eq!(st.reorder.reordered, 3, "5 before 4; 10 before 9 and 8");
}

#[test]
fn sent_units_are_emitted_or_dropped() {
    let mut s = Stream::new();
    let t = Instant::now();
    let mut ps = h264_units(3, 1, 40);
    ps.remove(20);
    ps.remove(10);
    let mut units = feed(&mut s, "10.0.0.1:7", &ps, t).len() as u64;
    s.tick(t + Duration::from_secs(1), &mut |_, _| units += 1);
    let st = s.stats();
    assert_eq!(st.sent, st.units + st.dropped);
    assert_eq!(st.units, units);
    assert_eq!(st.lost_packets, 2);
}
