#!/usr/bin/python3
"""rviz with hair_sim/HairDisplay in this process (python3-rviz: rviz's own VisualizationFrame, loaded from
a .rviz file), whose display properties are then changed one by one while it runs, as a user would in the
Displays panel. Started by hair_display_checks.py on its Xvfb display; not a test by itself.

usage: hair_display_live.py CONFIG.rviz OUT_DIR

After each step it takes a screenshot (/usr/bin/import, OUT_DIR/<step>.png) and records the display's
read-only properties. The last line on stdout is a JSON object: {"steps": [{"name", "png", "current_level",
"update_time", "messages"}...]} or {"error": "..."}; exit status 0, or 1 with an error.
"""
import json
import os
import subprocess
import sys
import time

from python_qt_binding.QtWidgets import QApplication
from rviz import bindings as rviz

START_TIMEOUT = 40.0  # s, until the display has drawn messages
SETTLE = 1.0  # s, after a change: a few messages (30 Hz) and frames (software rendering: ~10 fps)


def main():
    config_path, out_dir = sys.argv[1], sys.argv[2]
    app = QApplication([sys.argv[0]])
    frame = rviz.VisualizationFrame()
    frame.setSplashPath('')
    frame.initialize()
    config = rviz.Config()
    rviz.YamlConfigReader().readFile(config, config_path)
    frame.load(config)
    frame.resize(1280, 960)
    frame.move(0, 0)
    frame.show()
    manager = frame.getManager()
    root = manager.getRootDisplayGroup()
    display = None
    for i in range(root.numChildren()):
        child = root.childAt(i)
        if child.getName() == 'Hair':
            display = child
    if display is None:
        raise RuntimeError('no display named Hair in ' + config_path)

    def run(seconds):
        end = time.time() + seconds
        while time.time() < end:
            app.processEvents()
            time.sleep(0.005)

    def messages():
        """Messages received, from the display's status ("123 messages received"), 0 without."""
        for i in range(display.numChildren()):
            status = display.childAt(i)
            if status.getName().startswith('Status'):
                topic = status.subProp('Topic')
                words = str(topic.getValue()).split() if topic else []
                return int(words[0]) if words and words[0].isdigit() else 0
        return 0

    steps = []

    def step(name):
        run(SETTLE)
        png = os.path.join(out_dir, name + '.png')
        subprocess.run(['/usr/bin/import', '-window', 'root', png], check=True, timeout=30)
        steps.append({'name': name, 'png': png, 'messages': messages(),
                      'current_level': str(display.subProp('Current Level').getValue()),
                      'update_time': str(display.subProp('Update Time').getValue())})

    end = time.time() + START_TIMEOUT
    while messages() < 30 and time.time() < end:
        run(0.2)
    if messages() < 30:
        raise RuntimeError('the display received %d hair_state messages in %.0f s' % (messages(), START_TIMEOUT))
    run(2.0)  # the Update Time property averages 30 updates
    step('textured')
    display.subProp('Texture').setValue(False)
    step('untextured')
    display.subProp('Texture').setValue(True)
    display.subProp('Alpha Threshold').setValue(0.6)
    step('threshold_0.6')
    display.subProp('Alpha Threshold').setValue(0.05)
    override = display.subProp('Override Colour')
    override.subProp('Colour').setValue('255; 0; 0')
    override.setValue(True)
    step('override_red')
    override.setValue(False)
    for level in (0, 7, 3):
        display.subProp('Level of Detail').setValue(level)
        step('level_%d' % level)
    # Automatic level: the level of detail at a reference distance equal to the view's distance, then the
    # camera 4 x farther and 2 x closer.
    view = manager.getViewManager().getCurrent()
    distance = float(view.subProp('Distance').getValue())
    auto = display.subProp('Auto Level of Detail')
    auto.subProp('Reference Distance').setValue(distance)
    auto.setValue(True)
    step('auto_reference')
    view.subProp('Distance').setValue(4.0 * distance)
    step('auto_far')
    view.subProp('Distance').setValue(0.5 * distance)
    step('auto_near')
    auto.setValue(False)
    view.subProp('Distance').setValue(distance)
    display.subProp('Topic').setValue('/no_hair_here')
    step('other_topic')
    display.subProp('Topic').setValue('/hair_state')
    step('topic_back')
    print(json.dumps({'steps': steps}))
    sys.stdout.flush()
    os._exit(0)  # skip rviz's and Ogre's teardown: nothing to save, and it can hang on a virtual display


if __name__ == '__main__':
    try:
        main()
    except Exception as e:  # reported to the test as JSON
        print(json.dumps({'error': '%s: %s' % (type(e).__name__, e)}))
        sys.stdout.flush()
        os._exit(1)
