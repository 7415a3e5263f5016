#!/usr/bin/env node
/*
 * Interoperability, CiA 402 part: node-canopen (a CANopen master nobody on this project
 * wrote) drives one axis of a stepnode started with `profiles = ["cia402"]`.
 *
 *   node vcan-tests/interop/cia402.js --iface vcan0 --node 10
 *
 * node-canopen is a CiA 301 library: it has no CiA 402 layer, so the drive is driven as
 * CiA 402-2 tells any master to, through node-canopen's own SdoClient, Nmt and Pdo:
 *  - the controlword commands Shutdown 06h, Switch on 07h, Enable operation 0Fh are SDO
 *    downloads of 6040h; after each, 6041h is read (SDO upload) until the statusword
 *    shows the commanded state, decoded with the standard's masks (4Fh for Switch on
 *    disabled, 6Fh for Ready to switch on, Switched on, Operation enabled); the same state
 *    must reach node-canopen's PDO consumer through the node's TPDO1 {6041h, 6061h};
 *  - profile position mode (6060h = 1): target 607Ah, then the set-point handshake
 *    (controlword bit 4 new set-point -> statusword bit 12 set-point acknowledge -> bit 4
 *    cleared -> bit 12 cleared), target reached (bit 10, 0 while the axis moves), and
 *    6064h position actual value = the target; one absolute and one relative (bit 6) move.
 *    The position on the way is followed through node-canopen's PDO consumer of the
 *    node's TPDO2 {6064h, 606Ch}.
 *
 * Expects a freshly started node (pre-operational, default dictionary). One line per
 * check; exits 1 at the first failure with the frames of that check, 2 on bad arguments.
 * The frame log (raw socket) is only for those failure reports and for DLC checks.
 */
'use strict';

const { Device, DataType, NmtState, SdoError, rawToType } = require('canopen');
const can = require('socketcan');

// ------------------------------------------------------------------ arguments

function usage(msg) {
    if (msg)
        process.stderr.write(`cia402.js: ${msg}\n`);
    process.stderr.write('usage: node cia402.js --iface IFACE --node N [--master-id M] [--sdo-timeout MS] '
        + '[--state-timeout MS] [--timeout S]\n');
    process.exit(2);
}

function parseArgs(argv) {
    const opts = { masterId: 0x20, sdoTimeout: 4000, stateTimeout: 1000, timeout: 300 };
    const num = (name, v) => {
        const n = Number(v);
        if (v === undefined || !Number.isInteger(n))
            usage(`${name} needs an integer`);
        return n;
    };
    for (let i = 0; i < argv.length; ++i) {
        const a = argv[i];
        switch (a) {
            case '--iface': opts.iface = argv[++i]; break;
            case '--node': opts.node = num(a, argv[++i]); break;
            case '--master-id': opts.masterId = num(a, argv[++i]); break;
            case '--sdo-timeout': opts.sdoTimeout = num(a, argv[++i]); break;
            case '--state-timeout': opts.stateTimeout = num(a, argv[++i]); break;
            case '--timeout': opts.timeout = num(a, argv[++i]); break;
            case '-h': case '--help': usage();
            // fallthrough (usage exits)
            default: usage(`unknown argument ${a}`);
        }
    }
    if (!opts.iface) usage('--iface is required');
    if (!opts.node || opts.node < 1 || opts.node > 127) usage('--node must be 1..127');
    if (opts.masterId < 1 || opts.masterId > 127 || opts.masterId === opts.node)
        usage('--master-id must be 1..127 and differ from --node');
    return opts;
}

const opts = parseArgs(process.argv.slice(2));
const NODE = opts.node;
const T0 = Date.now();

// ------------------------------------------------------------------ CiA 402-2 words

// Objects of axis 1.
const CONTROLWORD = 0x6040;
const STATUSWORD = 0x6041;
const MODES_OF_OPERATION = 0x6060;
const MODES_DISPLAY = 0x6061;
const POSITION_ACTUAL = 0x6064;
const TARGET_POSITION = 0x607A;
const PROFILE_VELOCITY = 0x6081;
const PROFILE_ACCELERATION = 0x6083;
const PROFILE_DECELERATION = 0x6084;
const SUPPORTED_DRIVE_MODES = 0x6502;
const MODE_PP = 1;

// Controlword command coding (6040h; bits 7, 3..0).
const CW_SHUTDOWN = 0x06;
const CW_SWITCH_ON = 0x07;
const CW_ENABLE_OPERATION = 0x0F;
const CW_DISABLE_VOLTAGE = 0x00;
const CW_NEW_SET_POINT = 1 << 4; // pp
const CW_RELATIVE = 1 << 6; // pp: 607Ah is relative

// Statusword (6041h) state coding: mask, value.
const STATES = {
    'Not ready to switch on': [0x4F, 0x00],
    'Switch on disabled': [0x4F, 0x40],
    'Ready to switch on': [0x6F, 0x21],
    'Switched on': [0x6F, 0x23],
    'Operation enabled': [0x6F, 0x27],
    'Quick stop active': [0x6F, 0x07],
    'Fault reaction active': [0x4F, 0x0F],
    'Fault': [0x4F, 0x08],
};
const SW_TARGET_REACHED = 1 << 10;
const SW_SET_POINT_ACK = 1 << 12; // pp

const isState = (sw, name) => (sw & STATES[name][0]) === STATES[name][1];
const stateOf = (sw) => Object.keys(STATES).find((n) => isState(sw, n)) || 'no state';
const hex = (v, w = 8) => '0x' + (v >>> 0).toString(16).toUpperCase().padStart(w, '0');
const swText = (sw) => `${hex(sw, 4)} (${stateOf(sw)}${sw & SW_SET_POINT_ACK ? ', bit 12' : ''}`
    + `${sw & SW_TARGET_REACHED ? ', target reached' : ''})`;
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

class CheckError extends Error {}
function ensure(cond, msg) {
    if (!cond)
        throw new CheckError(msg);
}

// ------------------------------------------------------------------ node-canopen on the socket

const frames = [];
const fmtFrame = (f) => {
    const id = f.id.toString(16).toUpperCase().padStart(3, '0');
    return `${(f.t / 1000).toFixed(3).padStart(8)} ${f.dir} ${id}#${f.data.toString('hex').toUpperCase()}`;
};
const since = (m, pred = () => true) => frames.slice(m).filter(pred);

const channel = can.createRawChannel(opts.iface, true);
const master = new Device({ id: opts.masterId });
const sendFailures = [];
master.on('message', (m) => {
    frames.push({ t: Date.now() - T0, dir: 'tx', id: m.id, data: Buffer.from(m.data) });
    if (channel.send(m) < 0)
        sendFailures.push(m);
});
channel.addListener('onMessage', (m) => {
    if (m.ext || m.rtr)
        return;
    frames.push({ t: Date.now() - T0, dir: 'rx', id: m.id, data: Buffer.from(m.data) });
    master.receive(m);
});

master.eds.addSdoClientParameter(NODE, 0x600 + NODE, 0x580 + NODE);
master.eds.addHeartbeatConsumer(NODE, 10000);
master.eds.addEmcyConsumer(0x80 + NODE);

// Local objects node-canopen's RPDOs write (mirrors of the node's TPDO1 and TPDO2).
master.eds.addEntry(0x2200, { parameterName: 'node statusword (its TPDO1)', dataType: DataType.UNSIGNED16 });
master.eds.addEntry(0x2201, { parameterName: 'node modes display (its TPDO1)', dataType: DataType.INTEGER8 });
master.eds.addEntry(0x2202, { parameterName: 'node position actual (its TPDO2)', dataType: DataType.INTEGER32 });
master.eds.addEntry(0x2203, { parameterName: 'node velocity actual (its TPDO2)', dataType: DataType.INTEGER32 });

const hbChanges = [];
master.nmt.on('heartbeat', ({ deviceId, state }) => {
    if (deviceId === NODE)
        hbChanges.push({ t: Date.now() - T0, state });
});
const emergencies = [];
master.emcy.on('emergency', ({ cobId, em }) => emergencies.push({ t: Date.now() - T0, cobId, em }));
const statusPdos = []; // { t, sw, mode } from node-canopen's PDO consumer
const motionPdos = []; // { t, position, velocity }
master.pdo.on('pdo', (pdo) => {
    const v = pdo.dataObjects.map((o) => o.value);
    if (pdo.cobId === 0x180 + NODE)
        statusPdos.push({ t: Date.now() - T0, sw: v[0], mode: v[1] });
    else if (pdo.cobId === 0x280 + NODE)
        motionPdos.push({ t: Date.now() - T0, position: v[0], velocity: v[1] });
});

// ------------------------------------------------------------------ checks

let nChecks = 0;
let currentMark = 0;

async function check(name, fn) {
    currentMark = frames.length;
    const t = Date.now();
    try {
        const detail = await fn();
        nChecks += 1;
        console.log(`ok   ${name}${detail ? ': ' + detail : ''} (${Date.now() - t} ms)`);
    }
    catch (e) {
        fail(name, e);
    }
}

function fail(name, e) {
    const msg = (e instanceof CheckError) ? e.message
        : (e instanceof SdoError) ? `node-canopen: ${e.message} (abort code ${hex(e.code)})`
            : (e && e.stack) || String(e);
    console.log(`FAIL ${name}: ${msg}`);
    const fs_ = frames.slice(currentMark);
    const shown = fs_.slice(-60);
    console.log(`--- frames during this check (${fs_.length}${fs_.length > shown.length ? ', last 60 shown' : ''};`
        + ' time in s since start, rx = from the bus, tx = sent by node-canopen) ---');
    for (const f of shown)
        console.log(fmtFrame(f));
    if (emergencies.length)
        console.log(`--- EMCY: ${emergencies.map((x) => x.em.toString()).join('; ')}`);
    finish(1);
}

function finish(code) {
    try { master.stop(); }
    catch (e) { /* ignore */ }
    try { channel.stop(); }
    catch (e) { /* ignore */ }
    process.exit(code);
}

async function waitFor(what, pred, timeoutMs, pollMs = 10) {
    const deadline = Date.now() + timeoutMs;
    for (;;) {
        const v = await pred();
        if (v)
            return v;
        if (Date.now() > deadline)
            throw new CheckError(`timeout after ${timeoutMs} ms waiting for ${what}`);
        await sleep(pollMs);
    }
}

const upload = (index, subIndex = 0) => master.sdo.upload({
    deviceId: NODE, index, subIndex, timeout: opts.sdoTimeout,
});
const download = (index, subIndex, data, dataType) => master.sdo.download({
    deviceId: NODE, index, subIndex, data, dataType, timeout: opts.sdoTimeout,
});
const SIZE = {
    [DataType.INTEGER8]: 1, [DataType.UNSIGNED8]: 1, [DataType.UNSIGNED16]: 2,
    [DataType.INTEGER32]: 4, [DataType.UNSIGNED32]: 4,
};
async function read(index, dataType, subIndex = 0) {
    const raw = await upload(index, subIndex);
    ensure(Buffer.isBuffer(raw) && raw.length === SIZE[dataType],
        `${hex(index, 4)}:${subIndex} returned ${raw.length} byte(s) (${raw.toString('hex')}), `
        + `expected ${SIZE[dataType]}`);
    return rawToType(raw, dataType);
}
const statusword = () => read(STATUSWORD, DataType.UNSIGNED16);
const controlword = (cw) => download(CONTROLWORD, 0, cw, DataType.UNSIGNED16);

// Read 6041h until `pred`; every value read is kept (for the message on failure).
async function pollStatus(what, pred, timeoutMs = opts.stateTimeout) {
    const seen = [];
    try {
        return await waitFor(what, async () => {
            const sw = await statusword();
            if (!seen.length || seen[seen.length - 1] !== sw)
                seen.push(sw);
            return pred(sw) ? { sw, seen } : null;
        }, timeoutMs, 5);
    }
    catch (e) {
        if (e instanceof CheckError)
            throw new CheckError(`${e.message}; 6041h read: ${seen.map(swText).join(' -> ')}`);
        throw e;
    }
}

// A controlword command, then 6041h read until the state it commands; node-canopen's PDO
// consumer must see that state in the node's TPDO1 too.
async function command(cw, state) {
    const n0 = statusPdos.length;
    const t = Date.now();
    await controlword(cw);
    const { sw, seen } = await pollStatus(`6041h in '${state}' (sw & ${hex(STATES[state][0], 2)} == `
        + `${hex(STATES[state][1], 2)})`, (x) => isState(x, state));
    const pdo = await waitFor(`node-canopen's 'pdo' event of TPDO1 ${hex(0x180 + NODE, 3)} in '${state}'`,
        () => statusPdos.slice(n0).find((p) => isState(p.sw, state)), 1000);
    return `controlword ${hex(cw, 4)} -> 6041h ${swText(sw)} after ${Date.now() - t} ms`
        + `${seen.length > 1 ? ` (read ${seen.map((x) => hex(x, 4)).join(', ')})` : ''}; TPDO1 ${hex(pdo.sw, 4)}`;
}

// The profile set below (6081h, 6083h, 6084h): steps/s, steps/s^2.
const PROFILE = { velocity: 2000, acceleration: 8000, deceleration: 8000 };

// Duration of a rest-to-rest move on a linear (trapezoid) ramp, 6086h = 0.
function moveTime(distance) {
    const { velocity: v, acceleration: a, deceleration: d } = PROFILE;
    const ramps = v * v / (2 * a) + v * v / (2 * d);
    if (ramps > distance) { // triangle: the peak velocity is never reached
        const peak = Math.sqrt(2 * distance * a * d / (a + d));
        return peak / a + peak / d;
    }
    return v / a + (distance - ramps) / v + v / d;
}

// pp set-point: 607Ah, bit 4 -> bit 12, bit 4 cleared -> bit 12 cleared; then the move.
async function setPoint(target, relative, expectEnd) {
    const base = CW_ENABLE_OPERATION | (relative ? CW_RELATIVE : 0);
    const p0 = await read(POSITION_ACTUAL, DataType.INTEGER32);
    const m0 = motionPdos.length;
    await download(TARGET_POSITION, 0, target, DataType.INTEGER32);
    const t = Date.now();
    await controlword(base | CW_NEW_SET_POINT);
    const ack = await pollStatus('set-point acknowledge (6041h bit 12)', (sw) => sw & SW_SET_POINT_ACK);
    ensure(isState(ack.sw, 'Operation enabled'), `acknowledged in ${swText(ack.sw)}`);
    await controlword(base);
    await pollStatus('set-point acknowledge cleared', (sw) => !(sw & SW_SET_POINT_ACK), 5000);
    // Target reached is 0 while the axis moves to the new target, 1 when it is there.
    let moving = false;
    const reached = await pollStatus('target reached (6041h bit 10)', (sw) => {
        if (!(sw & SW_TARGET_REACHED))
            moving = true;
        return moving && (sw & SW_TARGET_REACHED);
    }, 10000);
    const took = Date.now() - t;
    const p = await read(POSITION_ACTUAL, DataType.INTEGER32);
    ensure(p === expectEnd, `6064h = ${p} at target reached, expected ${expectEnd} (from ${p0})`);
    ensure(isState(reached.sw, 'Operation enabled'), `target reached in ${swText(reached.sw)}`);
    const lo = Math.min(p0, expectEnd);
    const hi = Math.max(p0, expectEnd);
    const between = new Set(motionPdos.slice(m0).map((x) => x.position).filter((x) => x > lo && x < hi));
    ensure(between.size >= 3, `node-canopen's PDO consumer saw ${between.size} positions between ${p0} and `
        + `${expectEnd} on TPDO2 ${hex(0x280 + NODE, 3)}: the axis did not move there step by step`);
    const dlc = since(currentMark, (f) => f.dir === 'rx' && f.id === 0x280 + NODE && f.data.length !== 8);
    ensure(dlc.length === 0, `TPDO2 frames with DLC != 8: ${dlc.slice(0, 3).map(fmtFrame).join(', ')}`);
    // From the set-point to target reached as seen by polling 6041h: the profile's time,
    // plus the polling and SDO latency (generous: User-Mode Linux).
    const want = moveTime(Math.abs(expectEnd - p0)) * 1000;
    ensure(took >= want - 60 && took <= want + 500,
        `the move took ${took} ms from the set-point to target reached; the profile gives ${want.toFixed(0)} ms`);
    return `${p0} -> ${p} in ${took} ms (profile: ${want.toFixed(0)} ms; ack ${swText(ack.sw)}; `
        + `${between.size} positions on the way by TPDO2)`;
}

// ------------------------------------------------------------------ the session

async function main() {
    console.log(`node-canopen ${require('canopen/package.json').version} (master id ${opts.masterId}) `
        + `driving CiA 402 axis 1 of stepnode ${NODE} on ${opts.iface}`);
    channel.start();
    master.start();

    await check('heartbeat: node pre-operational', async () => {
        const h = await waitFor('a heartbeat with state pre-operational',
            () => hbChanges.find((x) => x.state === NmtState.PRE_OPERATIONAL), 5000);
        return `at ${(h.t / 1000).toFixed(2)} s`;
    });

    await check('1000h device type: CiA 402; 6502h supports pp', async () => {
        const type = await read(0x1000, DataType.UNSIGNED32);
        ensure((type & 0xFFFF) === 402, `1000h = ${hex(type)}, profile ${type & 0xFFFF}, expected 402`);
        const modes = await read(SUPPORTED_DRIVE_MODES, DataType.UNSIGNED32);
        ensure(modes & 1, `6502h = ${hex(modes)}: bit 0 (pp) clear`);
        return `1000h = ${hex(type)}, 6502h = ${hex(modes)}`;
    });

    await check('6041h after initialisation: Switch on disabled (transitions 0, 1)', async () => {
        const sw = await statusword();
        ensure(isState(sw, 'Switch on disabled'), `6041h = ${swText(sw)}`);
        return swText(sw);
    });

    await check('pp parameters: 6060h = 1 (6061h follows), 6081h/6083h/6084h', async () => {
        await download(MODES_OF_OPERATION, 0, MODE_PP, DataType.INTEGER8);
        const mode = await waitFor('6061h = 1', async () => {
            const m = await read(MODES_DISPLAY, DataType.INTEGER8);
            return m === MODE_PP ? m : null;
        }, 1000);
        const profile = [[PROFILE_VELOCITY, PROFILE.velocity], [PROFILE_ACCELERATION, PROFILE.acceleration],
            [PROFILE_DECELERATION, PROFILE.deceleration]];
        for (const [index, value] of profile) {
            await download(index, 0, value, DataType.UNSIGNED32);
            const back = await read(index, DataType.UNSIGNED32);
            ensure(back === value, `${hex(index, 4)} reads back ${back}, wrote ${value}`);
        }
        return `6061h = ${mode}; ${profile.map(([i, v]) => `${hex(i, 4)} = ${v}`).join(', ')}`;
    });

    await check('node-canopen RPDOs for the node\'s TPDO1 {6041h, 6061h} and TPDO2 {6064h, 606Ch}; NMT start',
        async () => {
            const map = [[0x1A00, [0x60410010, 0x60610008]], [0x1A01, [0x60640020, 0x606C0020]]];
            for (const [index, want] of map) {
                const n = await read(index, DataType.UNSIGNED8, 0);
                const entries = [];
                for (let s = 1; s <= want.length; ++s)
                    entries.push(await read(index, DataType.UNSIGNED32, s));
                ensure(n === want.length && entries.every((v, i) => v === want[i]),
                    `${hex(index, 4)} maps ${entries.map((v) => hex(v)).join(', ')}, expected CiA 402's `
                    + `${want.map((v) => hex(v)).join(', ')} (count ${n})`);
            }
            master.eds.addReceivePdo({
                cobId: 0x180 + NODE,
                dataObjects: [master.eds.getEntry(0x2200), master.eds.getEntry(0x2201)],
            });
            master.eds.addReceivePdo({
                cobId: 0x280 + NODE,
                dataObjects: [master.eds.getEntry(0x2202), master.eds.getEntry(0x2203)],
            });
            master.nmt.startNode(); // node-canopen itself operational: its Pdo module runs
            const t = Date.now() - T0;
            master.nmt.startNode(NODE);
            await waitFor('a heartbeat with state operational',
                () => hbChanges.find((x) => x.t >= t && x.state === NmtState.OPERATIONAL), 5000);
            return `RPDO ${hex(0x180 + NODE, 3)} -> 0x2200/0x2201, ${hex(0x280 + NODE, 3)} -> 0x2202/0x2203; `
                + 'node operational';
        });

    await check('Shutdown 06h -> Ready to switch on (transition 2)', () => command(CW_SHUTDOWN, 'Ready to switch on'));
    await check('Switch on 07h -> Switched on (transition 3)', () => command(CW_SWITCH_ON, 'Switched on'));
    await check('Enable operation 0Fh -> Operation enabled (transition 4)',
        () => command(CW_ENABLE_OPERATION, 'Operation enabled'));

    let end = 0;
    await check('pp absolute: 607Ah = 6064h + 1500, set-point handshake, target reached, 6064h', async () => {
        const p0 = await read(POSITION_ACTUAL, DataType.INTEGER32);
        end = p0 + 1500;
        return setPoint(end, false, end);
    });

    await check('pp relative (controlword bit 6): 607Ah = -600', async () => {
        const r = await setPoint(-600, true, end - 600);
        end -= 600;
        return r;
    });

    await check('Shutdown 06h -> Ready to switch on (transition 8); the axis stays', async () => {
        const r = await command(CW_SHUTDOWN, 'Ready to switch on');
        const p = await read(POSITION_ACTUAL, DataType.INTEGER32);
        ensure(p === end, `6064h = ${p} after Shutdown, was ${end}`);
        return r;
    });

    await check('Disable voltage 00h -> Switch on disabled (transition 7)',
        () => command(CW_DISABLE_VOLTAGE, 'Switch on disabled'));

    await check('no EMCY from the node during the session', async () => {
        const mine = emergencies.filter((e) => e.cobId === 0x80 + NODE);
        ensure(mine.length === 0, mine.map((e) => e.em.toString()).join('; '));
        ensure(sendFailures.length === 0, `${sendFailures.length} frames could not be sent`);
        return 'none';
    });

    console.log(`all ${nChecks} checks passed in ${((Date.now() - T0) / 1000).toFixed(2)} s (${frames.length} frames)`);
    finish(0);
}

const watchdog = setTimeout(() => {
    currentMark = Math.max(0, frames.length - 60);
    fail('whole session', new CheckError(`did not finish within --timeout ${opts.timeout} s`));
}, opts.timeout * 1000);
watchdog.unref();

main().catch((e) => fail('session', e));
