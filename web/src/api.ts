// The server's API (docs/serve.md): JSON requests, JSON or binary-frame answers, JSON errors.

export class ApiError extends Error {
  constructor(readonly status: number, message: string) {
    super(message);
  }
}

export interface Section {
  name: string;
  type: 'f32' | 'u32' | 'i16' | 'u8';
  count: number;
}

// A binary frame: "SVB1", u32 header length, JSON header, then typed sections (4-byte aligned).
export interface Frame {
  header: Record<string, any>;
  f32: Record<string, Float32Array>;
  u32: Record<string, Uint32Array>;
  i16: Record<string, Int16Array>;
  u8: Record<string, Uint8Array>;
}

export function parseFrame(buffer: ArrayBuffer): Frame {
  const view = new DataView(buffer);
  if (buffer.byteLength < 8 || view.getUint32(0, false) !== 0x53564231) {
    throw new ApiError(0, 'bad answer from the server (not a frame)');
  }
  const length = view.getUint32(4, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 8, length)));
  const frame: Frame = { header, f32: {}, u32: {}, i16: {}, u8: {} };
  let at = 8 + length;
  for (const s of header.sections as Section[]) {
    const size = s.type === 'u8' ? 1 : s.type === 'i16' ? 2 : 4;
    if (s.type === 'f32') frame.f32[s.name] = new Float32Array(buffer, at, s.count);
    else if (s.type === 'u32') frame.u32[s.name] = new Uint32Array(buffer, at, s.count);
    else if (s.type === 'i16') frame.i16[s.name] = new Int16Array(buffer, at, s.count);
    else frame.u8[s.name] = new Uint8Array(buffer, at, s.count);
    at += (s.count * size + 3) & ~3;
  }
  return frame;
}

// A drag preview's moves (docs/serve.md): the points whose bit is set in `mask` (bit i % 8 of
// byte i / 8), in order, and their new positions, `held` (x, y per point) plus the int16 steps of
// `offsets` times 2^-shift. In double, then rounded to float, as the server does: both then hold
// the same positions bit for bit.
export function decodeMoves(mask: Uint8Array, offsets: Int16Array, shift: number, held: Float32Array) {
  const indices = new Uint32Array(offsets.length / 2), values = new Float32Array(offsets.length);
  const step = 2 ** -shift;
  let k = 0;
  for (let i = 0; i < mask.length; ++i) {
    for (let b = mask[i]; b; b &= b - 1) {
      const g = 8 * i + 31 - Math.clz32(b & -b);
      indices[k] = g;
      values[2 * k] = held[2 * g] + offsets[2 * k] * step;
      values[2 * k + 1] = held[2 * g + 1] + offsets[2 * k + 1] * step;
      k++;
    }
  }
  return { indices, values };
}

async function check(response: Response): Promise<Response> {
  if (response.ok) return response;
  let message = `${response.status} ${response.statusText}`;
  try {
    const body = await response.json();
    if (body && typeof body.error === 'string') message = body.error;
  } catch {
    // not JSON: keep the status line
  }
  throw new ApiError(response.status, message);
}

export async function getJson<T = any>(path: string): Promise<T> {
  return (await check(await fetch(path, { cache: 'no-store' }))).json();
}

function post(path: string, body: unknown): Promise<Response> {
  return fetch(path, {
    method: 'POST',
    headers: { 'Content-Type': 'application/json' },
    body: JSON.stringify(body),
  }).then(check);
}

export async function postJson<T = any>(path: string, body: unknown): Promise<T> {
  return (await post(path, body)).json();
}

export async function postFrame(path: string, body: unknown): Promise<Frame> {
  return parseFrame(await (await post(path, body)).arrayBuffer());
}
