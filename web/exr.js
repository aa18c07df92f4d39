// A reader for the half-float RGBA OpenEXR files of an irid export:
// single-part scanline images, uncompressed, RLE, ZIPS or ZIP. The layout
// follows the OpenEXR file-format document ("The OpenEXR File Layout").
// A classic script (not a module) so that the page also opens from file://;
// it needs no other script (web/png16.js has its own inflate).
(function (ns) {
  'use strict';

  /** Inflates a zlib stream (an EXR ZIP block) through the browser's DecompressionStream. */
  async function inflateZlib(bytes) {
    const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('deflate'));
    return new Uint8Array(await new Response(stream).arrayBuffer());
  }

  const MAGIC = 20000630;
  const COMPRESSION_NAMES = ['none', 'RLE', 'ZIPS', 'ZIP', 'PIZ', 'PXR24', 'B44', 'B44A', 'DWAA', 'DWAB'];
  const LINES_PER_BLOCK = { 0: 1, 1: 1, 2: 1, 3: 16 };
  const HALF = 1;
  const FLOAT = 2;

  function readString(bytes, pos) {
    let end = pos;
    while (end < bytes.length && bytes[end] !== 0) end++;
    if (end >= bytes.length) throw new Error('header ends inside a name');
    return [new TextDecoder().decode(bytes.subarray(pos, end)), end + 1];
  }

  function readHeader(bytes, view, name) {
    let pos = 8;
    const attrs = {};
    for (;;) {
      let attrName;
      [attrName, pos] = readString(bytes, pos);
      if (attrName === '') break;
      let type;
      [type, pos] = readString(bytes, pos);
      if (pos + 4 > bytes.length) throw new Error(`${name}: truncated header`);
      const size = view.getInt32(pos, true);
      pos += 4;
      if (size < 0 || pos + size > bytes.length) throw new Error(`${name}: truncated header`);
      attrs[attrName] = { type, pos, size };
      pos += size;
    }
    return [attrs, pos];
  }

  function parseChannels(bytes, view, attr) {
    const channels = [];
    let pos = attr.pos;
    const end = attr.pos + attr.size;
    while (pos < end && bytes[pos] !== 0) {
      let channelName;
      [channelName, pos] = readString(bytes, pos);
      const pixelType = view.getInt32(pos, true);
      const xSampling = view.getInt32(pos + 8, true);
      const ySampling = view.getInt32(pos + 12, true);
      channels.push({ name: channelName, pixelType, xSampling, ySampling });
      pos += 16;
    }
    return channels;
  }

  /** Undoes OpenEXR's ZIP/RLE preprocessing: byte deltas, then the two halves interleaved. */
  function unpredict(t) {
    for (let i = 1; i < t.length; i++) t[i] = (t[i - 1] + t[i] - 128) & 0xff;
    const out = new Uint8Array(t.length);
    const half = (t.length + 1) >> 1;
    for (let i = 0, j = 0; j < t.length; i++) {
      out[j++] = t[i];
      if (j < t.length) out[j++] = t[half + i];
    }
    return out;
  }

  function unRle(src, expected) {
    const out = new Uint8Array(expected);
    let o = 0;
    let i = 0;
    while (i < src.length) {
      const count = (src[i] << 24) >> 24; // signed byte
      i++;
      if (count < 0) {
        const n = -count;
        if (o + n > expected || i + n > src.length) throw new Error('RLE data overruns the block');
        out.set(src.subarray(i, i + n), o);
        o += n;
        i += n;
      } else {
        const n = count + 1;
        if (o + n > expected || i >= src.length) throw new Error('RLE data overruns the block');
        out.fill(src[i], o, o + n);
        o += n;
        i++;
      }
    }
    if (o !== expected) throw new Error('RLE block is short');
    return out;
  }

  function halfToFloat(h) {
    const s = h & 0x8000 ? -1 : 1;
    const e = (h >> 10) & 0x1f;
    const f = h & 0x3ff;
    if (e === 0) return s * f * 2 ** -24;
    if (e === 31) return f ? NaN : s * Infinity;
    return s * (1 + f / 1024) * 2 ** (e - 15);
  }

  /**
   * Decodes an RGBA(or RGB) half/float scanline EXR into
   * {width, height, data: Float32Array RGBA} in file row order
   * (the first stored row first). Throws an Error naming the problem.
   */
  async function decodeExr(buffer, name = 'EXR') {
    const bytes = new Uint8Array(buffer);
    const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    if (bytes.length < 8 || view.getInt32(0, true) !== MAGIC) throw new Error(`${name}: not an OpenEXR file`);
    const flags = view.getUint32(4, true);
    if (flags & 0x200) throw new Error(`${name}: tiled EXR files are not supported`);
    if (flags & 0x1800) throw new Error(`${name}: multi-part or deep EXR files are not supported`);
    let attrs;
    let pos;
    try {
      [attrs, pos] = readHeader(bytes, view, name);
    } catch (e) {
      throw new Error(e.message.startsWith(name) ? e.message : `${name}: ${e.message}`);
    }
    for (const key of ['channels', 'compression', 'dataWindow']) {
      if (!attrs[key]) throw new Error(`${name}: header lacks "${key}"`);
    }
    const compression = bytes[attrs.compression.pos];
    if (!(compression in LINES_PER_BLOCK)) {
      throw new Error(`${name}: ${COMPRESSION_NAMES[compression] ?? compression} compression is not supported (use none, RLE, ZIPS or ZIP)`);
    }
    const dw = attrs.dataWindow.pos;
    const xMin = view.getInt32(dw, true);
    const yMin = view.getInt32(dw + 4, true);
    const width = view.getInt32(dw + 8, true) - xMin + 1;
    const height = view.getInt32(dw + 12, true) - yMin + 1;
    if (width <= 0 || height <= 0) throw new Error(`${name}: empty data window`);
    // Channels are stored in the header's (alphabetical) order.
    const channels = parseChannels(bytes, view, attrs.channels);
    for (const c of channels) {
      if (c.pixelType !== HALF && c.pixelType !== FLOAT) throw new Error(`${name}: channel ${c.name} is not half or float`);
      if (c.xSampling !== 1 || c.ySampling !== 1) throw new Error(`${name}: channel ${c.name} is subsampled`);
    }
    const slot = { R: 0, G: 1, B: 2, A: 3 };
    for (const needed of ['R', 'G', 'B']) {
      if (!channels.some((c) => c.name === needed)) throw new Error(`${name}: no ${needed} channel`);
    }
    const linesPerBlock = LINES_PER_BLOCK[compression];
    const blocks = Math.ceil(height / linesPerBlock);
    const data = new Float32Array(width * height * 4);
    for (let i = 0; i < width * height; i++) data[i * 4 + 3] = 1;
    const lineBytes = channels.reduce((n, c) => n + width * (c.pixelType === HALF ? 2 : 4), 0);
    if (pos + blocks * 8 > bytes.length) throw new Error(`${name}: truncated offset table`);
    for (let b = 0; b < blocks; b++) {
      const offset = Number(view.getBigUint64(pos + b * 8, true));
      if (offset + 8 > bytes.length) throw new Error(`${name}: truncated (block ${b} lies past the end)`);
      const y0 = view.getInt32(offset, true) - yMin;
      const size = view.getInt32(offset + 4, true);
      const lines = Math.min(linesPerBlock, height - y0);
      if (y0 < 0 || y0 >= height || size < 0 || offset + 8 + size > bytes.length) {
        throw new Error(`${name}: truncated or corrupt block ${b}`);
      }
      const expected = lines * lineBytes;
      let block = bytes.subarray(offset + 8, offset + 8 + size);
      if (size < expected) {
        // A block that would not shrink is stored raw, whatever the compression.
        try {
          if (compression === 1) block = unpredict(unRle(block, expected));
          else block = unpredict(await inflateZlib(block));
        } catch (e) {
          throw new Error(`${name}: block ${b} does not decompress (${e.message})`);
        }
      }
      if (block.length !== expected) throw new Error(`${name}: block ${b} holds ${block.length} bytes, ${expected} expected`);
      const bv = new DataView(block.buffer, block.byteOffset, block.byteLength);
      let p = 0;
      for (let l = 0; l < lines; l++) {
        const row = y0 + l;
        for (const c of channels) {
          const s = slot[c.name];
          for (let x = 0; x < width; x++) {
            let v;
            if (c.pixelType === HALF) {
              v = halfToFloat(bv.getUint16(p, true));
              p += 2;
            } else {
              v = bv.getFloat32(p, true);
              p += 4;
            }
            if (s !== undefined) data[(row * width + x) * 4 + s] = v;
          }
        }
      }
    }
    return { width, height, data };
  }

  ns.decodeExr = decodeExr;
})((window.IridWeb = window.IridWeb || {}));
