// A script module (docs/scripting.md): the fleet's fastest boat, kept up to date in
// root.fleet_watch, on the module's own serial executor, never on the frame thread.
//
//   [modules.fleet_watch]
//   kind = "script"
//   file = "fleet_watch.js"
//
// It sees the DataServer's API only (`mocu.read/write/subscribe/call/create/after`), with the
// sandbox and the operation budget of every script: no file or network access.

const out = mocu.create("root", "fleet_watch", "watch");
const speeds = {};

function publish() {
    let fastest = "", top = -1;
    for (const name in speeds) {
        if (speeds[name] !== undefined && speeds[name] > top) {
            fastest = name;
            top = speeds[name];
        }
    }
    mocu.write(out + ".fastest", fastest);
    mocu.write(out + ".top_speed", top < 0 ? 0 : top);
    mocu.write(out + ".reporting", Object.keys(speeds).filter(n => speeds[n] !== undefined).length);
}

for (const name of ["usv1", "usv2"]) {
    // Follows discovery: the boat need not exist yet; `undefined` while it is absent.
    mocu.subscribe("vehicles." + name + ".nav.speed", v => {
        speeds[name] = v;
        publish();
    });
}
