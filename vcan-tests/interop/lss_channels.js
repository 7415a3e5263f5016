#!/usr/bin/env node
/*
 * Interoperability, issue 12: node-canopen (npm "canopen", CiA 301/305) as the LSS master
 * that gives an unconfigured stepnode its node-ID, and as an SDO client on a second SDO
 * server channel of that node.
 *
 *   node vcan-tests/interop/lss_channels.js --iface vcan0 --serial S --node N
 *
 * Every LSS request and SDO transfer is node-canopen's (Lss#fastscan, #configureNodeId,
 * #storeConfiguration, #switchModeGlobal; SdoClient#upload/#download with an SDO client
 * parameter per channel, Eds#addSdoClientParameter); only the boot-up and which COB-ID an
 * answer came on are read off the socket. Expects one node on the bus without a node-ID
 * (started with --node-id none --serial-number S). One line per check; exit 1 at the first
 * failure, 2 on bad arguments.
 */
'use strict';

const { Device, DataType, LssMode } = require('canopen');
const can = require('socketcan');

function parseArgs(argv) {
    const opts = {};
    for (let i = 0; i < argv.length; i += 2)
        opts[argv[i].replace(/^--/, '')] = argv[i + 1];
    const node = Number(opts.node), serial = Number(opts.serial);
    if (!opts.iface || !Number.isInteger(node) || node < 1 || node > 126 || !Number.isInteger(serial)) {
        process.stderr.write('usage: node lss_channels.js --iface IFACE --serial S --node N (1..126)\n');
        process.exit(2);
    }
    return { iface: opts.iface, node, serial };
}

const opts = parseArgs(process.argv.slice(2));
const NODE = opts.node;
const MASTER = 0x7E;
// Channel 2 (0x1201) on CAN-IDs of the range CiA 301 7.3.5 leaves to such use (README,
// "SDO channels").
const CH2_RX = 0x690 + NODE % 0x40;  // client -> server
const CH2_TX = 0x6D0 + NODE % 0x10;  // server -> client
const hex = (v) => '0x' + (v >>> 0).toString(16).toUpperCase();

const channel = can.createRawChannel(opts.iface, true);
const master = new Device({ id: MASTER, enableLss: false });
const heard = []; // { id, data } from the bus
master.on('message', (m) => channel.send(m));
channel.addListener('onMessage', (m) => {
    if (m.ext || m.rtr)
        return;
    heard.push({ id: m.id, data: Buffer.from(m.data) });
    master.receive(m);
});

async function check(name, fn) {
    try {
        const detail = await fn();
        console.log(`ok   ${name}${detail ? ': ' + detail : ''}`);
    }
    catch (e) {
        console.log(`FAIL ${name}: ${(e && e.stack) || e}`);
        console.log('frames heard: ' + heard.slice(-30).map((f) => `${hex(f.id)}#${f.data.toString('hex')}`).join(' '));
        process.exit(1);
    }
}
function ensure(cond, msg) {
    if (!cond)
        throw new Error(msg);
}
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
async function waitFor(pred, ms) {
    for (const end = Date.now() + ms; Date.now() < end; await sleep(10)) {
        const v = pred();
        if (v)
            return v;
    }
    return undefined;
}

const upload = (index, subIndex, dataType, cobIdRx) => master.sdo.upload({
    deviceId: NODE, index, subIndex, dataType, cobIdRx, timeout: 3000,
});

async function main() {
    channel.start();
    master.start();
    master.lss.start(); // the LSS master's answers (0x7E4) reach node-canopen's Lss

    await check('LSS fast scan finds the unconfigured node (CiA 305)', async () => {
        const found = await master.lss.fastscan({ timeout: 60 });
        ensure(found, 'no unconfigured node answered');
        ensure(found.serialNumber === opts.serial, `serial ${hex(found.serialNumber)}, expected ${hex(opts.serial)}`);
        ensure(found.productCode === 0x53544550, `product ${hex(found.productCode)}`);
        return `vendor ${hex(found.vendorId)} product ${hex(found.productCode)} `
            + `revision ${hex(found.revisionNumber)} serial ${hex(found.serialNumber)}`;
    });

    await check(`configure node-ID ${NODE}, store, switch to waiting: boot-up`, async () => {
        await master.lss.configureNodeId(NODE, 500);
        await master.lss.storeConfiguration(500);
        const from = heard.length;
        master.lss.switchModeGlobal(LssMode.OPERATION);
        const boot = await waitFor(() => heard.slice(from).find(
            (f) => f.id === 0x700 + NODE && f.data.length === 1 && f.data[0] === 0), 5000);
        ensure(boot, `no boot-up on ${hex(0x700 + NODE)}`);
    });

    master.eds.addSdoClientParameter(NODE, 0x600 + NODE, 0x580 + NODE);
    await check('the default channel: 0x1018:4 is the serial number', async () => {
        const v = await upload(0x1018, 4, DataType.UNSIGNED32, 0x580 + NODE);
        ensure(v === opts.serial, `read ${hex(v)}`);
    });

    await check(`SDO server channel 2 (0x1201) configured over the default one: ${hex(CH2_RX)} / ${hex(CH2_TX)}`, async () => {
        const write = (sub, data, dataType) => master.sdo.download({
            deviceId: NODE, index: 0x1201, subIndex: sub, data, dataType, cobIdRx: 0x580 + NODE, timeout: 3000,
        });
        await write(1, CH2_RX, DataType.UNSIGNED32);
        await write(2, CH2_TX, DataType.UNSIGNED32);
        await write(3, MASTER, DataType.UNSIGNED8);
        master.eds.addSdoClientParameter(NODE, CH2_RX, CH2_TX);
    });

    await check('both channels at once: the device name (segmented) on each, answers on their own COB-IDs', async () => {
        const from = heard.length;
        const [a, b] = await Promise.all([
            upload(0x1008, 0, DataType.VISIBLE_STRING, 0x580 + NODE),
            upload(0x1008, 0, DataType.VISIBLE_STRING, CH2_TX),
        ]);
        ensure(a === b && a.length > 4, `"${a}" and "${b}"`);
        const on = (id) => heard.slice(from).filter((f) => f.id === id).length;
        ensure(on(CH2_TX) >= 2 && on(0x580 + NODE) >= 2, `answers: ${on(0x580 + NODE)} default, ${on(CH2_TX)} channel 2`);
        return `"${a}"; ${on(0x580 + NODE)} answers on ${hex(0x580 + NODE)}, ${on(CH2_TX)} on ${hex(CH2_TX)}`;
    });

    master.stop();
    channel.stop();
    process.exit(0);
}

main();
