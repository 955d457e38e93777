// The peer of alight's MAVLink conformance test (test/mavlink/conformance_test.cpp): node-mavlink
// from the npm registry, pinned in package-lock.json, an implementation no one here wrote.
//
//   node mavlink_peer.mjs decode --key HEX < frames.bin
//       splits and decodes the frames alight encoded; one JSON line per frame: header, checksum as
//       received and as node-mavlink computes it, signature check against the key, and every
//       field by its XML name; then one summary line with node-mavlink's own counters.
//   node mavlink_peer.mjs encode --key HEX
//       one JSON line per frame node-mavlink encoded (hex bytes plus the values it was given): every
//       message alight knows as MAVLink 2, signed MAVLink 2, MAVLink 1 (ids < 256) and all-zero.
//   node mavlink_peer.mjs bench --key HEX
//       node-mavlink's encode and parse throughput on a stream like bench/mavlink's (20 rounds of
//       every message, unsigned and signed, read in 64-byte pieces), the benchmark's peer figures.
//
// Field values: 64-bit integers as decimal strings, NaN / Infinity / -0 as strings ("NaN",
// "Infinity", "-Infinity", "-0"), char arrays as strings.
// exit: 0 done, 2 usage, 77 node-mavlink not installed (cd test/mavlink/conformance && npm ci)

import path from 'node:path';
import { Readable } from 'node:stream';

const SKIP = 77;
let mav;
try {
  mav = await import('node-mavlink');
} catch (e) {
  const dir = path.dirname(new URL(import.meta.url).pathname);
  console.error(`node-mavlink not installed (cd ${dir} && npm ci): ${e.message}`);
  process.exit(SKIP);
}
const {
  MavLinkPacketSplitter, MavLinkPacketParser, MavLinkProtocolV1, MavLinkProtocolV2, x25crc,
  minimal, common, standard,
} = mav;

// The messages of alight/mavlink/messages.hpp.
const IDS = [0, 1, 20, 22, 26, 31, 32, 48, 49, 76, 77, 82, 84, 105, 108, 111, 115, 138, 148, 245, 253, 256, 331];
const REGISTRY = { ...minimal.REGISTRY, ...common.REGISTRY, ...standard.REGISTRY };

const args = process.argv.slice(2);
const mode = args[0];
const keyIndex = args.indexOf('--key');
if (!['decode', 'encode', 'bench'].includes(mode) || keyIndex < 0 || !/^[0-9a-f]{64}$/i.test(args[keyIndex + 1])) {
  console.error('usage: node mavlink_peer.mjs decode|encode|bench --key HEX(64)');
  process.exit(2);
}
const key = Buffer.from(args[keyIndex + 1], 'hex');

function jsonValue(v) {
  if (typeof v === 'bigint') return v.toString();
  if (typeof v === 'number') {
    if (Number.isNaN(v)) return 'NaN';
    if (v === Infinity) return 'Infinity';
    if (v === -Infinity) return '-Infinity';
    if (Object.is(v, -0)) return '-0';
    return v;
  }
  if (Array.isArray(v)) return v.map(jsonValue);
  return v;
}

function fieldsOf(clazz, data) {
  const out = {};
  for (const f of clazz.FIELDS) out[f.source] = jsonValue(data[f.name]);
  return out;
}

function givenFields(clazz, message) {
  const out = {};
  for (const f of clazz.FIELDS) {
    let v = message[f.name];
    if (f.type === 'float') v = Math.fround(v);
    if (f.type === 'float[]') v = v.map(Math.fround);
    out[f.source] = jsonValue(v);
  }
  return out;
}

async function readStdin() {
  const chunks = [];
  for await (const c of process.stdin) chunks.push(c);
  return Buffer.concat(chunks);
}

async function decode() {
  const input = await readStdin();
  const splitter = new MavLinkPacketSplitter();
  const packets = [];
  const done = new Promise((resolve, reject) => {
    const stream = Readable.from([input]).pipe(splitter).pipe(new MavLinkPacketParser());
    stream.on('data', (p) => packets.push(p));
    stream.on('end', resolve);
    stream.on('error', reject);
  });
  await done;
  for (const p of packets) {
    const h = p.header;
    const clazz = REGISTRY[h.msgid];
    const signed = p.signature !== null && p.signature !== undefined;
    const trim = signed ? 13 + 2 : 2;
    const line = {
      version: h.magic === MavLinkProtocolV2.START_BYTE ? 2 : 1,
      msgid: h.msgid,
      name: clazz ? clazz.MSG_NAME : null,
      len: h.payloadLength,
      incompat_flags: h.incompatibilityFlags,
      compat_flags: h.compatibilityFlags,
      seq: h.seq,
      sysid: h.sysid,
      compid: h.compid,
      crc: p.crc,
      crc_computed: clazz ? x25crc(p.buffer, 1, trim, clazz.MAGIC_NUMBER) : null,
      signed,
      fields: clazz ? fieldsOf(clazz, p.protocol.data(p.payload, clazz)) : null,
    };
    if (signed) {
      line.link_id = p.signature.linkId;
      line.timestamp = String(p.signature.timestamp);
      line.signature_ok = p.signature.matches(key);
    }
    console.log(JSON.stringify(line));
  }
  console.log(JSON.stringify({
    summary: {
      packets: packets.length,
      valid: splitter.validPackages,
      invalid: splitter.invalidPackages,
      unknown: splitter.unknownPackagesCount,
    },
  }));
}

// Distinct values for every field, from a small deterministic generator (not alight's scheme).
function makeFiller(seed) {
  let s = seed >>> 0;
  const rnd = () => {
    s = (Math.imul(s, 1664525) + 1013904223) >>> 0;
    return s;
  };
  const intOf = (type) => {
    switch (type) {
      case 'uint8_t': case 'uint8_t_mavlink_version': return 1 + (rnd() % 255);
      case 'int8_t': return (rnd() % 2 ? -1 : 1) * (1 + (rnd() % 127));
      case 'uint16_t': return 1 + (rnd() % 65535);
      case 'int16_t': return (rnd() % 2 ? -1 : 1) * (1 + (rnd() % 32767));
      case 'uint32_t': return 1 + (rnd() % 0xffffffff);
      case 'int32_t': return (rnd() % 2 ? -1 : 1) * (1 + (rnd() % 0x7fffffff));
      case 'uint64_t': return (BigInt(rnd()) << 32n) | BigInt(rnd()) | (1n << 63n);
      case 'int64_t': return -((BigInt(rnd() & 0x7fffffff) << 32n) | BigInt(rnd()) | 1n);
      case 'float': {
        // Values that are not floats (Math.fround rounds them): the encoder's rounding is checked.
        const v = (rnd() / 4294967296 - 0.5) * 10 ** ((rnd() % 9) - 3);
        return v === 0 ? 0.125 : v;
      }
      case 'double': return (rnd() / 4294967296 - 0.5) * 1e6;
      default: throw new Error(`no filler for ${type}`);
    }
  };
  return (clazz) => {
    const m = new clazz();
    for (const f of clazz.FIELDS) {
      if (f.type === 'char[]') {
        const chars = 'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789 .,:;!?-+=()"\\/';
        let t = '';
        for (let i = 0; i < f.length; i++) t += chars[rnd() % chars.length];
        m[f.name] = t;
      } else if (f.type.endsWith('[]')) {
        const base = f.type.slice(0, -2);
        m[f.name] = Array.from({ length: f.length }, () => intOf(base));
      } else {
        m[f.name] = intOf(f.type);
      }
    }
    return m;
  };
}

function zeroOf(clazz) {
  const m = new clazz();
  for (const f of clazz.FIELDS) {
    const zero = f.type.startsWith('int64') || f.type.startsWith('uint64') ? 0n : 0;
    if (f.type === 'char[]') m[f.name] = '';
    else if (f.type.endsWith('[]')) m[f.name] = Array.from({ length: f.length }, () => zero);
    else m[f.name] = zero;
  }
  return m;
}

function encode() {
  const SYSID = 1, COMPID = 1, LINK_ID = 3;
  const v2 = new MavLinkProtocolV2(SYSID, COMPID);
  const v2signed = new MavLinkProtocolV2(SYSID, COMPID, MavLinkProtocolV2.IFLAG_SIGNED);
  const v1 = new MavLinkProtocolV1(SYSID, COMPID);
  const fill = makeFiller(20111);
  const signBaseMs = Date.UTC(2026, 0, 2, 3, 4, 5);  // fixed: the output is reproducible
  let seq = 0;
  const emit = (kind, protocol, clazz, message, signMs) => {
    let buffer = protocol.serialize(message, seq);
    const line = { kind, seq, msgid: clazz.MSG_ID, name: clazz.MSG_NAME };
    if (signMs !== undefined) {
      buffer = protocol.sign(buffer, LINK_ID, key, signMs);
      line.link_id = LINK_ID;
      line.timestamp = String((signMs - MavLinkProtocolV2.SIGNATURE_START_TIME) * 100);
    }
    // The values given, as the wire holds them (floats rounded to float32), and whether
    // node-mavlink's own decoder reads the same back from the bytes it wrote.
    line.fields = givenFields(clazz, message);
    const payloadOffset = protocol instanceof MavLinkProtocolV2 ? 10 : 6;
    const payload = Buffer.concat([buffer.subarray(payloadOffset, payloadOffset + buffer[1]),
                                   Buffer.alloc(255 - buffer[1])]);
    line.roundtrip_ok =
        JSON.stringify(fieldsOf(clazz, protocol.data(payload, clazz))) === JSON.stringify(line.fields);
    line.hex = buffer.toString('hex');
    console.log(JSON.stringify(line));
    seq = (seq + 1) & 255;
  };
  let signCount = 0;
  for (const id of IDS) {
    const clazz = REGISTRY[id];
    emit('v2', v2, clazz, fill(clazz));
    emit('v2_signed', v2signed, clazz, fill(clazz), signBaseMs + 10 * signCount++);
    if (id < 256) emit('v1', v1, clazz, fill(clazz));
    emit('v2_zero', v2, clazz, zeroOf(clazz));
  }
}

async function bench() {
  const fill = makeFiller(7);
  const messages = [];
  for (let r = 0; r < 20; r++) for (const id of IDS) messages.push(fill(REGISTRY[id]));
  const signBaseMs = Date.UTC(2026, 0, 2, 3, 4, 5);
  const encodeAll = (signed) => {
    const protocol = new MavLinkProtocolV2(1, 1, signed ? MavLinkProtocolV2.IFLAG_SIGNED : 0);
    return messages.map((m, i) => {
      const b = protocol.serialize(m, i & 255);
      return signed ? protocol.sign(b, 1, key, signBaseMs + i) : b;
    });
  };
  // Wall time per frame over at least 2 s of repetitions.
  const time = async (what, frames, fn) => {
    let runs = 0;
    const start = process.hrtime.bigint();
    let elapsed = 0;
    while (elapsed < 2e9) {
      await fn();
      runs++;
      elapsed = Number(process.hrtime.bigint() - start);
    }
    const perFrameNs = elapsed / (runs * frames);
    console.log(JSON.stringify({ what, frames_per_second: Math.round(1e9 / perFrameNs),
                                 ns_per_frame: Math.round(perFrameNs) }));
  };
  for (const signed of [false, true]) {
    await time(`encode${signed ? ' signed' : ''}`, messages.length, () => { encodeAll(signed); });
    const stream = Buffer.concat(encodeAll(signed));
    await time(`parse and decode${signed ? ', signature checked' : ''}`, messages.length, () =>
      new Promise((resolve, reject) => {
        let n = 0;
        const pieces = [];
        for (let i = 0; i < stream.length; i += 64) pieces.push(stream.subarray(i, i + 64));
        const out = Readable.from(pieces).pipe(new MavLinkPacketSplitter())
          .pipe(new MavLinkPacketParser());
        out.on('data', (p) => {
          if (signed && !p.signature.matches(key)) reject(new Error('bad signature'));
          p.protocol.data(p.payload, REGISTRY[p.header.msgid]);
          n++;
        });
        out.on('end', () => (n === messages.length ? resolve() : reject(new Error(`${n} frames`))));
      }));
  }
}

if (mode === 'decode') await decode();
else if (mode === 'encode') encode();
else await bench();
