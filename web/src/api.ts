/// REST calls under `/api` (docs/protocol.md, "REST"): same origin, token from the page address.
import type { CompileResult, FileEntry, FileList, FileText, GenerationDiff, GraphGroups, ProgramStatus, SaveResult, TestDraft } from "./messages.gen";

// The REST results are defined once, in server/protocol/rest.py, and generated into messages.gen.ts.
export type { ChangedFile, CompileResult, FileEntry, FileText, GenerationDiff, ProgramStatus, SaveResult, TestDraft } from "./messages.gen";
import type { OptionGroup } from "./graphgroups";

/// The token of a server that requires one: `?token=` of the page address.
export const token: string | null = new URLSearchParams(globalThis.location?.search ?? "").get("token");

/// The page's folder on the server: `/`, or `/replay/ID/` and `/fork/ID/` for a studio served beside
/// the main one; every address of the page is relative to it.
export function basePath(): string {
  const path = globalThis.location?.pathname ?? "/";
  return path.slice(0, path.lastIndexOf("/") + 1) || "/";
}

/// The websocket address on the page's origin (under the page's folder).
export function websocketUrl(): string {
  const loc = globalThis.location;
  const scheme = loc.protocol === "https:" ? "wss:" : "ws:";
  return `${scheme}//${loc.host}${basePath()}ws${token ? `?token=${encodeURIComponent(token)}` : ""}`;
}

/// A JSON request under `api/` (for modules of their own; the answer's `detail` on an error).
export async function apiJson<T>(method: string, path: string, body?: unknown): Promise<T> {
  const { status, data } = await request<T>(method, path, body);
  if (status >= 400) throw new ApiError((data as { detail?: string })?.detail ?? `${method} ${path}: HTTP ${status}`, status, data);
  return data;
}

export class ApiError extends Error {
  constructor(
    message: string,
    readonly status: number,
    readonly body: unknown,
  ) {
    super(message);
  }
}

function headers(extra: Record<string, string> = {}): Record<string, string> {
  const h: Record<string, string> = { ...extra };
  if (token) h.Authorization = `Bearer ${token}`;
  return h;
}

async function request<T>(method: string, path: string, body?: unknown, extra: Record<string, string> = {}): Promise<{ status: number; data: T }> {
  const init: RequestInit = { method, headers: headers(body === undefined ? extra : { "Content-Type": "application/json", ...extra }) };
  if (body !== undefined) init.body = JSON.stringify(body);
  const response = await fetch(`api/${path}`, init);
  const text = await response.text();
  let data: unknown = text;
  try {
    data = text ? JSON.parse(text) : null;
  } catch {
    /* not JSON: keep the text */
  }
  if (!response.ok && ![409, 422].includes(response.status)) {
    const detail = (data as { detail?: unknown })?.detail;
    throw new ApiError(typeof detail === "string" ? detail : `${method} ${path}: HTTP ${response.status}`, response.status, data);
  }
  return { status: response.status, data: data as T };
}




const encodePath = (path: string): string => path.split("/").map(encodeURIComponent).join("/");

export async function listFiles(): Promise<FileEntry[]> {
  return (await request<FileList>("GET", "files")).data.files;
}

export async function readFile(path: string): Promise<FileText> {
  return (await request<FileText>("GET", `files/${encodePath(path)}`)).data;
}

/// Save with `If-Match`: `conflict` carries the version on disk when someone else saved first.
export async function writeFile(path: string, text: string, version: string): Promise<{ status: number; result: SaveResult; conflict: { version: string } | null }> {
  const { status, data } = await request<SaveResult & { version: string }>("PUT", `files/${encodePath(path)}`, { text }, { "If-Match": `"${version}"` });
  if (status === 409) return { status, result: data, conflict: { version: data?.version } };
  return { status, result: data, conflict: null };
}

export async function createFile(path: string, text: string): Promise<{ status: number; result: SaveResult }> {
  const { status, data } = await request<SaveResult>("POST", `files/${encodePath(path)}`, { text });
  if (status === 409) throw new ApiError(`${path} exists already`, 409, data);
  return { status, result: data };
}


/// Compile with unsaved text for one file (nothing saved or swapped).
export async function compile(path: string, text: string): Promise<CompileResult> {
  const { data } = await request<CompileResult>("POST", "compile", { path, text });
  return data;
}

const svgCache = new Map<string, Promise<string>>();

/// An SVG of `/api/graph/...` (cached per address; the server caches by content hash too).
/// `collapse`: grouped by folder, with these group keys collapsed (`COLLAPSE_SEPARATOR`-joined;
/// "" none, "*" all); undefined: the plain graph.
export function graphSvg(program: string, option?: string | number, agent?: string, root?: string, collapse?: string): Promise<string> {
  let path = `graph/${encodeURIComponent(program)}`;
  if (option !== undefined) path += `/${encodeURIComponent(String(option))}`;
  const query: string[] = [];
  if (root) query.push(`root=${encodeURIComponent(root)}`);
  else if (agent) query.push(`agent=${encodeURIComponent(agent)}`);
  if (collapse !== undefined) query.push(`collapse=${encodeURIComponent(collapse)}`);
  if (query.length) path += `?${query.join("&")}`;
  let svg = svgCache.get(path);
  if (!svg) {
    svg = fetch(`api/${path}`, { headers: headers() }).then(async (r) => {
      if (!r.ok) throw new ApiError(`graph: HTTP ${r.status} ${await r.text()}`, r.status, null);
      return r.text();
    });
    svg.catch(() => svgCache.delete(path));
    svgCache.set(path, svg);
  }
  return svg;
}

/// The option groups of an option graph (`/api/graph-groups`): source folders or name prefixes.
export async function graphGroups(program: string, agent?: string, root?: string): Promise<OptionGroup[]> {
  const query = root ? `?root=${encodeURIComponent(root)}` : agent ? `?agent=${encodeURIComponent(agent)}` : "";
  const r = await fetch(`api/graph-groups/${encodeURIComponent(program)}${query}`, { headers: headers() });
  if (!r.ok) throw new ApiError(`graph groups: HTTP ${r.status} ${await r.text()}`, r.status, null);
  return ((await r.json()) as GraphGroups).groups;
}


/// The behavior sets of `GET /api/status`.
export async function programStatus(): Promise<Record<string, ProgramStatus>> {
  const { data } = await request<{ programs: Record<string, ProgramStatus> }>("GET", "status");
  return data.programs;
}

/// Forget cached SVGs (a hot reload changes graphs).
export function clearGraphCache(): void {
  svgCache.clear();
}


export async function draftTest(body: unknown): Promise<TestDraft> {
  const { status, data } = await request<TestDraft & { detail?: string }>("POST", "tests/draft", body);
  if (status === 409 || status === 422) throw new ApiError(data?.detail ?? `tests/draft: HTTP ${status}`, status, data);
  return data;
}



/// `GET /api/generations/{n}/diff` (an ApiError with status 404 when the server keeps it no more).
export async function generationDiff(n: number): Promise<GenerationDiff> {
  const { data } = await request<GenerationDiff>("GET", `generations/${n}/diff`);
  return data;
}

/// A file under `api/` (a picture): its bytes and the name the server gave it (Content-Disposition).
export async function apiFile(path: string, params: Record<string, string | number | undefined>): Promise<{ blob: Blob; filename: string }> {
  const query = new URLSearchParams();
  for (const [key, value] of Object.entries(params)) if (value !== undefined) query.set(key, String(value));
  const response = await fetch(`api/${path}?${query.toString()}`, { headers: headers() });
  if (!response.ok) {
    let detail = `GET ${path}: HTTP ${response.status}`;
    try {
      const body = (await response.json()) as { detail?: unknown };
      if (typeof body.detail === "string") detail = body.detail;
    } catch {
      /* not JSON: keep the status */
    }
    throw new ApiError(detail, response.status, null);
  }
  const disposition = response.headers.get("Content-Disposition") ?? "";
  const filename = /filename="([^"]+)"/.exec(disposition)?.[1] ?? `picture.${String(params.format ?? "svg")}`;
  return { blob: await response.blob(), filename };
}
