"""The add-on with Blender's interface running (a window under a virtual X server): the modal
Simulate operator as a user starts it, while the interface keeps its event loop turning, and
Esc stopping it (tests/blender/run_ui.sh):

  xvfb-run -a blender --factory-startup --enable-event-simulate --python-exit-code 1 \
      --python tests/blender/ui_check.py -- --zip ZIP --python-dir DIR --models MODELS

1. Simulate is invoked in the Properties editor (INVOKE_DEFAULT: invoke + modal timer).
   While it runs - preprocessing included - a 20 ms application timer keeps firing: the
   largest gap between two of its calls stays within 1 s and 3 x the largest with the
   interface idle (redraws cost a software renderer that much), so the interface is not
   frozen; the panel's progress rises and the status names the frames; it ends with 21
   frames on the timeline.
2. A second, long run is stopped by a simulated Esc key press: it ends "cancelled" with the
   frames done kept.
Exits 0 when both hold, 1 otherwise (a message says what failed).
"""

import argparse
import os
import sys
import time

import bpy

argv = sys.argv[sys.argv.index("--") + 1:]
parser = argparse.ArgumentParser()
for name in ("--zip", "--python-dir", "--models"):
    parser.add_argument(name, required=True)
args = parser.parse_args(argv)

bpy.ops.preferences.addon_install(filepath=os.path.abspath(args.zip), overwrite=True)
bpy.ops.preferences.addon_enable(module="sem_blender")
from sem_blender import sem_package, simulation  # noqa: E402

sem_package.preferences().python_path = os.path.abspath(args.python_dir)
state = {"phase": "start", "ticks": [], "progress": [], "status": [], "t0": 0.0, "error": None}


def fail(message):
    state["error"] = message
    print("ui_check: FAILED: " + message, flush=True)
    sys.stderr.flush()
    os._exit(1)  # from a timer, the only way to give the shell a failing status


def properties_override():
    window = bpy.context.window_manager.windows[0]
    area = max(window.screen.areas, key=lambda a: a.width * a.height)
    area.type = "PROPERTIES"
    region = [r for r in area.regions if r.type == "WINDOW"][0]
    return {"window": window, "screen": window.screen, "area": area, "region": region}


def step():
    """An application timer: drives the check and measures how often it gets to run."""
    now = time.monotonic()
    state["ticks"].append(now)
    scene = bpy.context.scene
    try:
        if state["phase"] == "start":
            bpy.ops.import_scene.sem_model(filepath=os.path.join(args.models, "rocket",
                                                                 "rocket.iges"))
            root = [o for o in scene.objects if "sem_model_path" in o][0]
            root.sem.pin_mode = "BOX"
            root.sem.pin_box_max = (1.0, 1.0, 0.01)
            root.sem.youngs_modulus = 1e5
            scene.sem.gravity = (0.0, -9.81, 0.0)
            scene.sem.frames = 20
            properties_override()  # the Properties editor in the window, drawn from now on
            state.update(phase="idle", t0=now, ticks=[now])
        elif state["phase"] == "idle":
            # the timer's rhythm with the interface idle (redraws on a software renderer)
            if now - state["t0"] < 4.0:
                return 0.02
            gaps = [b - a for a, b in zip(state["ticks"], state["ticks"][1:])]
            state["idle_gap"] = max(gaps[len(gaps) // 2:])
            with bpy.context.temp_override(**properties_override()):
                result = bpy.ops.sem.simulate("INVOKE_DEFAULT")
            if result != {"RUNNING_MODAL"}:
                return fail("Simulate did not start modal: %s (%s)" % (result, scene.sem.status))
            state.update(phase="running", t0=now, ticks=[now])
        elif state["phase"] == "running":
            state["progress"].append(scene.sem.progress)
            state["status"].append(scene.sem.status)
            if simulation.active() is None:
                gaps = [b - a for a, b in zip(state["ticks"], state["ticks"][1:])]
                root = [o for o in scene.objects if "sem_model_path" in o][0]
                if root.get("sem_frame_count") != 21:
                    return fail("after the run: %s frames (%s)" % (root.get("sem_frame_count"),
                                                                  scene.sem.status))
                frames_seen = sorted({s for s in state["status"] if s.startswith("frame")})
                print("ui_check: modal run of 20 frames in %.1f s: %d timer calls, largest gap "
                      "%.2f s (idle: %.2f s), progress seen %s, %d distinct frame lines in the "
                      "status, ended '%s'"
                      % (now - state["t0"], len(gaps), max(gaps), state["idle_gap"],
                         sorted({round(p) for p in state["progress"]}), len(frames_seen),
                         scene.sem.status), flush=True)
                if max(gaps) > max(1.0, 3 * state["idle_gap"]) or len(gaps) < 10:
                    return fail("the interface stalled: %d timer calls, largest gap %.2f s"
                                % (len(gaps), max(gaps)))
                if len(frames_seen) < 3:
                    return fail("the status showed %d frame lines" % len(frames_seen))
                scene.sem.frames = 400
                with bpy.context.temp_override(**properties_override()):
                    bpy.ops.sem.simulate("INVOKE_DEFAULT")
                state.update(phase="cancel", t0=now)
        elif state["phase"] == "cancel":
            run = simulation.active()
            if run is not None and run.frames_done >= 3 and not run.cancel_event.is_set():
                window = bpy.context.window_manager.windows[0]
                window.event_simulate(type="ESC", value="PRESS")
                window.event_simulate(type="ESC", value="RELEASE")
            elif run is None:
                status = scene.sem.status
                if not status.startswith("cancelled after"):
                    return fail("Esc: the run ended '%s'" % status)
                print("ui_check: Esc: %s" % status, flush=True)
                print("ui_check: passed", flush=True)
                bpy.ops.wm.quit_blender()
                return None
            elif now - state["t0"] > 120:
                return fail("Esc did not stop the run")
    except Exception as e:  # reported, not lost in a timer
        import traceback
        traceback.print_exc()
        return fail("%s: %s" % (type(e).__name__, e))
    return 0.02


bpy.app.timers.register(step, first_interval=1.0)
