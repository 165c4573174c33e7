/// What the studio's uPlot charts share (the Plot panel and the Dual Dynamics panel): axes over
/// seconds in the page's theme colours, and the timeline cursor drawn as a vertical line.
import type uPlot from "uplot";
import type { Session } from "../session";

/// The two axes of a chart over seconds: `digits` fractional digits on x, `ySize` px for y labels.
export function timeAxes(digits: number, ySize: number): uPlot.Axis[] {
  const style = getComputedStyle(document.documentElement);
  const fg = style.getPropertyValue("--muted").trim() || "#999";
  const grid = style.getPropertyValue("--grid").trim() || "rgba(128,128,128,0.2)";
  return [
    { stroke: fg, grid: { stroke: grid }, ticks: { stroke: grid }, values: (_u, vals) => vals.map((v) => `${v.toFixed(digits)}s`) },
    { stroke: fg, grid: { stroke: grid }, ticks: { stroke: grid }, size: ySize },
  ];
}

/// A draw hook marking the session's cursor (timeline ms; the chart's x is in seconds).
export function cursorHook(session: Session): (u: uPlot) => void {
  return (u) => {
    const cursor = session.cursor;
    if (cursor === null) return;
    const x = u.valToPos(cursor / 1000, "x", true);
    const ctx = u.ctx;
    ctx.save();
    ctx.strokeStyle = "#ffd54a";
    ctx.lineWidth = 2;
    ctx.beginPath();
    ctx.moveTo(x, u.bbox.top);
    ctx.lineTo(x, u.bbox.top + u.bbox.height);
    ctx.stroke();
    ctx.restore();
  };
}
