/// The "Export" menu of the option graph and the option view: SVG, PNG or PDF of what the view
/// shows, downloaded as a file (`GET api/picture/...`, server/api/pictures.py). "With the active
/// path" adds what the selected robot ran at the tick in view (the server draws it from the ticks
/// it keeps; a tick it no longer keeps is said, not guessed).
import { apiFile } from "../api";
import { h, toast } from "../ui";

/// What to draw: the route under `api/` and its parameters (without the format).
export interface PictureTarget {
  path: string;
  params: Record<string, string | number | undefined>;
  /// the robot and tick in view, added when "with the active path" is ticked
  tick?: { robot: number; seq: number };
}

export const PICTURE_FORMATS = ["svg", "png", "pdf"] as const;

/// Fetch the picture and hand it to the browser as a download.
export async function downloadPicture(target: PictureTarget, format: string, withTick: boolean): Promise<string> {
  const params = { ...target.params, format, ...(withTick && target.tick ? target.tick : {}) };
  const { blob, filename } = await apiFile(target.path, params);
  const url = URL.createObjectURL(blob);
  const link = h("a", { href: url, download: filename, hidden: true });
  document.body.append(link);
  link.click();
  link.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10_000);
  return filename;
}

/// The menu: a button that opens three formats and the active-path switch.
export function exportMenu(target: () => PictureTarget | null, what: string): HTMLElement {
  const withTick = h("input", { type: "checkbox", checked: true, "aria-label": "with the active path" });
  const items = PICTURE_FORMATS.map((format) =>
    h(
      "button",
      {
        role: "menuitem",
        title: `Download ${what} as ${format.toUpperCase()}`,
        onclick: () => {
          menu.open = false;
          const chosen = target();
          if (!chosen) {
            toast("Nothing to export yet", "error");
            return;
          }
          downloadPicture(chosen, format, withTick.checked)
            .then((name) => toast(`Saved ${name}`, "ok"))
            .catch((e: Error) => toast(`Export failed: ${e.message}`, "error"));
        },
      },
      format.toUpperCase(),
    ),
  );
  const menu = h(
    "details.export-menu",
    {},
    h("summary", { title: `Export ${what} as a picture` }, "Export"),
    h("div.export-items", { role: "menu", "aria-label": `Export ${what}` }, ...items, h("label.export-tick", {}, withTick, "with the active path")),
  );
  return menu;
}
