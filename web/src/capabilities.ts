/// What the host of a robot allows, from the `attached` list of an attached session's scene
/// (`xabsl attach`: each host's `capabilities`). A NaoTH robot (`xabsl attach naoth://...`) cannot
/// be forced, overridden, paused or stepped: the panels say so instead of offering it.
import type { Session } from "./session";

type AttachedHost = { name: string; kind?: string; capabilities?: Record<string, boolean> };

/// Why `robot`'s host cannot do `what` (`force`, `override`, `pause`), or null when it can (or
/// the session runs its own world).
export function unavailable(session: Session, robot: number, what: "force" | "override" | "pause"): string | null {
  const info = session.robotInfo(robot) as { host?: string } | undefined;
  const attached = (session.scene as { attached?: AttachedHost[] } | null)?.attached;
  const host = attached?.find((a) => a.name === info?.host) ?? (attached?.length === 1 ? attached[0] : undefined);
  if (!host || host.capabilities?.[what] !== false) return null;
  const who = host.kind === "naoth" ? "A NaoTH robot" : `Host ${host.name}`;
  const verb = what === "force" ? "cannot be forced" : what === "override" ? "cannot have its inputs overridden" : "cannot be paused";
  return `${who} ${verb}: its debug port has no command for it (docs/naoth.md). Agent selection and upload + reload work.`;
}
