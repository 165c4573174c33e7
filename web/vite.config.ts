// Vite builds the studio into web/dist; the server serves it at `/` and answers `/api` and `/ws`
// on the same origin. `npm run dev` proxies both to a running `xabsl serve` (XABSL_SERVER).
import { defineConfig } from "vitest/config";

declare const process: { env: Record<string, string | undefined> };
const server = process.env.XABSL_SERVER ?? "http://127.0.0.1:8000";

export default defineConfig({
  base: "./",
  build: { outDir: "dist", emptyOutDir: true, sourcemap: false, chunkSizeWarningLimit: 1200 },
  server: {
    proxy: {
      "/api": server,
      "/ws": { target: server.replace(/^http/, "ws"), ws: true },
      "/lsp": { target: server.replace(/^http/, "ws"), ws: true },
    },
  },
  test: { environment: "node", include: ["test/**/*.test.ts"] },
});
