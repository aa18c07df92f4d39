// A decoder for the 16-bit PNGs of an irid export. Browsers decode <img>
// PNGs to 8 bits per channel, which would throw away the precision the
// export stores, so the file is parsed here: chunks, zlib through the
// browser's DecompressionStream, then the five scanline filters.
// A classic script (not a module) so that the page also opens from file://;
// it needs no other script.
(function (ns) {
  'use strict';

  const SIGNATURE = [137, 80, 78, 71, 13, 10, 26, 10];

  /** Inflates a zlib stream (PNG IDAT data). */
  async function inflateZlib(bytes) {
    const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('deflate'));
    return new Uint8Array(await new Response(stream).arrayBuffer());
  }

  function paeth(a, b, c) {
    const p = a + b - c;
    const pa = Math.abs(p - a);
    const pb = Math.abs(p - b);
    const pc = Math.abs(p - c);
    if (pa <= pb && pa <= pc) return a;
    return pb <= pc ? b : c;
  }

  /**
   * Decodes a non-interlaced 16-bit RGB or RGBA PNG.
   * Returns {width, height, channels: 4, data: Uint16Array} with RGBA samples
   * in file row order (A = 65535 for RGB files). Throws an Error naming what
   * is wrong for anything else.
   */
  async function decodePng16(buffer, name = 'PNG') {
    const bytes = new Uint8Array(buffer);
    const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    if (bytes.length < 8 || SIGNATURE.some((b, i) => bytes[i] !== b)) {
      throw new Error(`${name}: not a PNG file`);
    }
    let pos = 8;
    let header = null;
    const idat = [];
    let ended = false;
    while (pos + 8 <= bytes.length) {
      const length = view.getUint32(pos);
      const type = String.fromCharCode(...bytes.subarray(pos + 4, pos + 8));
      const start = pos + 8;
      if (start + length + 4 > bytes.length) throw new Error(`${name}: truncated in chunk ${type}`);
      const body = bytes.subarray(start, start + length);
      if (type === 'IHDR') {
        header = {
          width: view.getUint32(start),
          height: view.getUint32(start + 4),
          depth: body[8],
          colorType: body[9],
          interlace: body[12],
        };
      } else if (type === 'IDAT') {
        idat.push(body);
      } else if (type === 'IEND') {
        ended = true;
        break;
      }
      pos = start + length + 4; // skip the CRC
    }
    if (!header) throw new Error(`${name}: no IHDR chunk`);
    if (!ended) throw new Error(`${name}: truncated (no IEND chunk)`);
    const { width, height, depth, colorType, interlace } = header;
    if (depth !== 16 || (colorType !== 6 && colorType !== 2)) {
      throw new Error(`${name}: expected 16-bit RGB or RGBA, found bit depth ${depth}, colour type ${colorType}`);
    }
    if (interlace !== 0) throw new Error(`${name}: interlaced PNGs are not supported`);
    if (width === 0 || height === 0) throw new Error(`${name}: empty image`);

    let compressed = new Uint8Array(idat.reduce((n, c) => n + c.length, 0));
    let offset = 0;
    for (const chunk of idat) {
      compressed.set(chunk, offset);
      offset += chunk.length;
    }
    let raw;
    try {
      raw = await inflateZlib(compressed);
    } catch (e) {
      throw new Error(`${name}: image data does not inflate (${e.message})`);
    }
    const fileChannels = colorType === 6 ? 4 : 3;
    const bpp = fileChannels * 2; // bytes per pixel, the filters' unit
    const stride = width * bpp;
    if (raw.length < height * (stride + 1)) {
      throw new Error(`${name}: image data holds ${raw.length} bytes, ${height * (stride + 1)} expected`);
    }
    const out = new Uint16Array(width * height * 4);
    let prev = new Uint8Array(stride);
    let line = new Uint8Array(stride);
    for (let y = 0; y < height; y++) {
      const rowStart = y * (stride + 1);
      const filter = raw[rowStart];
      const src = raw.subarray(rowStart + 1, rowStart + 1 + stride);
      for (let i = 0; i < stride; i++) {
        const a = i >= bpp ? line[i - bpp] : 0;
        const b = prev[i];
        const c = i >= bpp ? prev[i - bpp] : 0;
        let v;
        switch (filter) {
          case 0: v = src[i]; break;
          case 1: v = src[i] + a; break;
          case 2: v = src[i] + b; break;
          case 3: v = src[i] + ((a + b) >> 1); break;
          case 4: v = src[i] + paeth(a, b, c); break;
          default: throw new Error(`${name}: row ${y} has unknown filter ${filter}`);
        }
        line[i] = v & 0xff;
      }
      for (let x = 0; x < width; x++) {
        const o = (y * width + x) * 4;
        for (let ch = 0; ch < fileChannels; ch++) {
          const p = x * bpp + ch * 2;
          out[o + ch] = (line[p] << 8) | line[p + 1];
        }
        if (fileChannels === 3) out[o + 3] = 65535;
      }
      [prev, line] = [line, prev];
    }
    return { width, height, channels: 4, data: out };
  }

  ns.decodePng16 = decodePng16;
})((window.IridWeb = window.IridWeb || {}));
