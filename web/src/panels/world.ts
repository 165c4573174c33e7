/// What the world panels (dynamics, plan, facts) share: the world's own commands (op
/// `world_command`, docs/protocol.md), the scene keys a Dual Dynamics / plan world carries, and
/// the generic form that renders any world command from its description.
///
/// Nothing here knows a world by name: a world announces `panels` and `commands` in its static
/// scene, and its dynamic scene carries the keys typed below (examples/errands/world.py is one).
import type { Connection } from "../connection";
import type { DynamicScene, StaticScene } from "../protocol";
import type { Session } from "../session";
import { h, toast } from "../ui";

export interface WorldCommandArg {
  name: string;
  type: "enum" | "number" | "bool" | "string";
  choices?: string[];
  default?: unknown;
}

export interface WorldCommand {
  name: string;
  label: string;
  group: string;
  doc?: string;
  args: WorldCommandArg[];
}

/// The Dual Dynamics and plan part of a dynamic scene.
export interface DDScene extends DynamicScene {
  alpha?: number[];
  s?: Record<string, number>;
  op?: string | null;
  plan_status?: string;
  facts?: string[];
  truth?: string[];
  tentative?: string[];
  fact_events?: number;
  plan_version?: number;
  done?: string[];
  forced_op?: string | null;
  op_since?: number;
  op_timeout?: number | null;
  terms?: Record<string, number[]>;
  fusion?: Record<string, { value: number; decay: number; shares: number[] }>;
}

export interface DDStatic {
  behaviors: string[];
  actuators: string[];
  theta: number[];
  terms: string[];
}

export function panelsOf(scene: StaticScene | null): string[] {
  const p = scene?.panels;
  return Array.isArray(p) ? (p.filter((x) => typeof x === "string") as string[]) : [];
}

export function commandsOf(scene: StaticScene | null): WorldCommand[] {
  const c = scene?.commands;
  return Array.isArray(c) ? (c as WorldCommand[]) : [];
}

export function ddOf(scene: StaticScene | null): DDStatic | null {
  const dd = scene?.dd as DDStatic | undefined;
  return dd && Array.isArray(dd.behaviors) ? dd : null;
}

export function sceneOf(session: Session): DDScene | null {
  return (session.view?.scene as DDScene | null | undefined) ?? null;
}

/// Run one world command; rejects with the server's message.
export function worldCommand<T = unknown>(connection: Connection, name: string, args: Record<string, unknown> = {}): Promise<T> {
  return connection.command("world_command", { name, args }) as Promise<T>;
}

/// One form per command of `group`: its arguments as selects/inputs and a button to run it.
export function commandForms(connection: Connection, commands: WorldCommand[], groups: string[], done?: (name: string, result: unknown) => void): HTMLElement {
  const forms = commands
    .filter((c) => groups.includes(c.group))
    .map((c) => {
      const inputs = c.args.map((a) => {
        let el: HTMLInputElement | HTMLSelectElement;
        if (a.type === "enum") {
          el = h("select", { "aria-label": `${c.label}: ${a.name}`, "data-arg": a.name }, ...(a.choices ?? []).map((x) => h("option", { value: x }, x)));
          el.value = String(a.default ?? a.choices?.[0] ?? "");
        } else if (a.type === "bool") {
          el = h("select", { "aria-label": `${c.label}: ${a.name}`, "data-arg": a.name }, h("option", { value: "true" }, "true"), h("option", { value: "false" }, "false"));
          el.value = String(a.default ?? true);
        } else {
          el = h("input", { "aria-label": `${c.label}: ${a.name}`, "data-arg": a.name, type: a.type === "number" ? "number" : "text", size: 6 });
          el.value = String(a.default ?? "");
        }
        return { arg: a, el };
      });
      const run = (): void => {
        const args: Record<string, unknown> = {};
        for (const { arg, el } of inputs) {
          args[arg.name] = arg.type === "bool" ? el.value === "true" : arg.type === "number" ? Number(el.value) : el.value;
        }
        worldCommand(connection, c.name, args)
          .then((result) => {
            const what = (result as { done?: string } | null)?.done;
            toast(what ? `Done: ${what}` : `${c.label}: done`, "ok");
            done?.(c.name, result);
          })
          .catch((e: Error) => toast(`${c.label}: ${e.message}`, "error", 6000));
      };
      return h(
        "div.world-command",
        { "data-command": c.name, title: c.doc ?? "" },
        h("button", { onclick: run, "data-run": c.name }, c.label),
        ...inputs.map(({ el }) => el),
      );
    });
  return h("div.world-commands", {}, ...forms);
}

/// Colours for behavior / operator series (stable by index).
export const SERIES = ["#4fc3f7", "#ffb74d", "#81c784", "#e57373", "#ba68c8", "#fff176", "#4db6ac", "#f06292", "#a1887f", "#90a4ae"];

export function seconds(ms: number): string {
  return `${(ms / 1000).toFixed(1)} s`;
}
