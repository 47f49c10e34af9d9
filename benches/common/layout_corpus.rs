//! The generated layout the check benchmarks measure (benches/check.rs and
//! compiler/language/examples/check_speed.rs share this one copy).

/// A layout of `lines` lines: stdlib-like components, windows, widgets, bindings, watches.
pub fn generate(lines: usize) -> String {
    let mut s = String::from("use \"stdlib/gauges.mocu\"\nlet kn = 1.94384\n");
    let mut i = 0;
    let mut count = 2;
    while count < lines {
        let block = format!(
            "let v{i} = root.vehicles.usv{i}\n\
             window w{i} {{ layer {i}  rect 0 0 400 300  opacity 0.9 }}\n\
             in w{i} {{\n\
             \x20 speed{i}: Dial {{ at 10 10 100 100  value v{i}.nav.speed * kn  range 0 .. 40  alarm value > 35 }}\n\
             \x20 fuel{i}: Bar {{ at 10 120 100 16  value v{i}.fuel ?? 0  warn value < 0.2 }}\n\
             \x20 hdg{i}: Label {{ at 10 140  text \"HDG {{v{i}.nav.heading:03.0}}° {{v{i}.name ?? \"?\"}}\" }}\n\
             }}\n\
             component C{i}(value: number?, max: number = 1) {{\n\
             \x20 let f = clamp((value ?? 0) / max, 0, 1)\n\
             \x20 rounded 0 0 w h 3  fill #141c24  stroke #3a4a5a\n\
             \x20 rect 1 1 ((w - 2) * f) (h - 2)  fill if f < 0.2 then #f59e0b else #22c55e\n\
             }}\n\
             watch low{i} {{ when v{i}.fuel < 0.15 for 5s then alert warning \"Fuel low on {{v{i}.name}}\" }}\n\
             bind keyboard {{ key f{k} -> set v{i}.nav.goal_throttle = 10  call v{i}.stop() }}\n",
            k = i % 12 + 1
        );
        count += block.lines().count();
        s.push_str(&block);
        i += 1;
    }
    s
}

/// The standard library files the generated layout uses, for a check that reads no disk.
#[allow(dead_code)] // Not every file that includes this module checks.
pub fn stdlib_loader() -> mocu_language::MemoryLoader {
    mocu_language::MemoryLoader::new()
        .with("stdlib/gauges.mocu", include_str!("../../stdlib/gauges.mocu"))
        .with("stdlib/theme.mocu", include_str!("../../stdlib/theme.mocu"))
}
