#!/usr/bin/python3
"""rviz with hair_sim/HairDisplay in this process (python3-rviz: rviz's own VisualizationFrame, loaded from
a .rviz file), whose display properties are then changed one by one while it runs, as a user would in the
Displays panel. Started by hair_display_checks.py on its Xvfb display; not a test by itself.

usage: hair_display_live.py CONFIG.rviz OUT_DIR
       hair_display_live.py --publish TOPIC  (a HairState publisher at 10 Hz until killed: the one that goes away)

After each step it takes a screenshot (/usr/bin/import, OUT_DIR/<step>.png) and records the display's
read-only properties and status. The last line on stdout is a JSON object: {"steps": [{"name", "png",
"current_level", "update_time", "messages", "status"}...]} or {"error": "..."}; exit status 0, or 1 with an
error. "status" maps each entry of the display's status (Topic, Transform, Strips, Vertices...) to its text.

After the property steps, hostile input (steps named hostile_*): messages published from this process (rospy,
latched, frame world) on HOSTILE_TOPIC: strips with bad colours, with control points near FLT_MAX or
10,000 km away, a 1000 x 1000 grid and 20,000 strips (both
over the display's vertex budget), a frame that tf does not know, the automatic level with a huge Reference Distance, the Unreliable box with
a publisher that has no UDP, a topic of another type, an empty topic, and a publisher (another process) that
goes away.
"""
import json
import math
import os
import subprocess
import sys
import time

START_TIMEOUT = 40.0  # s, until the display has drawn messages
SETTLE = 1.0  # s, after a change: a few messages (30 Hz) and frames (software rendering: ~10 fps)
HOSTILE_TOPIC = '/hair_display_hostile'
GONE_TOPIC = '/hair_display_gone'
STATUS_TIMEOUT = 8.0  # s, for a status the display sets after its topic check (every 2 s without messages)


def strip_state(i, n=20, columns=2, rows=5, top=1.6):
    """Strip i of a synthetic crown of n strips, hanging from z = top (m; 1.6: around the view's focal point)."""
    from hair_sim_msgs.msg import StripState
    a = 2.0 * math.pi * i / n
    xyz = []
    for r in range(rows):
        for c in range(columns):
            radius = 0.1 + 0.01 * r
            xyz += [radius * math.cos(a + 0.08 * c), radius * math.sin(a + 0.08 * c), top - 0.06 * r]
    s = StripState(columns=columns, rows=rows, hair_length=0.25, xyz=xyz)
    s.color.r, s.color.g, s.color.b, s.color.a = 0.45, 0.3, 0.15, 1.0
    return s


def hair_state(n=20, top=1.6):
    import rospy
    from hair_sim_msgs.msg import HairState
    msg = HairState()
    msg.header.frame_id = 'world'
    msg.header.stamp = rospy.Time.now()
    msg.strips = [strip_state(i, n, top=top) for i in range(n)]
    return msg


def publish(topic):
    """--publish TOPIC: a plain publisher that the test kills (a publisher that goes away)."""
    import rospy
    from hair_sim_msgs.msg import HairState
    rospy.init_node('hair_display_gone_publisher', anonymous=True)
    pub = rospy.Publisher(topic, HairState, queue_size=2)
    rate = rospy.Rate(10)
    while not rospy.is_shutdown():
        pub.publish(hair_state())
        rate.sleep()


def main():
    from python_qt_binding.QtWidgets import QApplication
    from rviz import bindings as rviz
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

    def status():
        """The display's status entries: {name: text}."""
        out = {}
        for i in range(display.numChildren()):
            group = display.childAt(i)
            if group.getName().startswith('Status'):
                for j in range(group.numChildren()):
                    out[str(group.childAt(j).getName())] = str(group.childAt(j).getValue())
        return out

    def wait_status(key, text, timeout=STATUS_TIMEOUT):
        """Runs rviz until the status entry key contains text, or timeout s."""
        end = time.time() + timeout
        while text not in status().get(key, '') and time.time() < end:
            run(0.1)

    steps = []

    def step(name, settle=SETTLE):
        run(settle)
        png = os.path.join(out_dir, name + '.png')
        subprocess.run(['/usr/bin/import', '-window', 'root', png], check=True, timeout=30)
        steps.append({'name': name, 'png': png, 'messages': messages(),
                      'current_level': str(display.subProp('Current Level').getValue()),
                      'update_time': str(display.subProp('Update Time').getValue()), 'status': status()})

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
    wait_status('Topic', 'nothing publishes')
    step('other_topic')
    display.subProp('Topic').setValue('/hair_state')
    step('topic_back')
    hostile(display, run, step, wait_status, messages, status)
    print(json.dumps({'steps': steps}))
    sys.stdout.flush()
    os._exit(0)  # skip rviz's and Ogre's teardown: nothing to save, and it can hang on a virtual display


def hostile(display, run, step, wait_status, messages, status):
    """Hostile and broken input, as the module's docstring lists; each step records the display's status."""
    import rospy
    from hair_sim_msgs.msg import HairState
    rospy.init_node('hair_display_live', anonymous=True, disable_signals=True)
    pub = rospy.Publisher(HOSTILE_TOPIC, HairState, queue_size=1, latch=True)
    topic = display.subProp('Topic')
    topic.setValue(HOSTILE_TOPIC)
    run(0.5)  # the last messages of /hair_state, queued before the change, are through

    def send(msg):
        """Publishes msg and runs rviz until the display has received it (one more message counted)."""
        run(0.1)  # the status of what came before
        before = messages()
        pub.publish(msg)
        end = time.time() + 30.0
        while messages() <= before and time.time() < end:
            run(0.1)

    send(hair_state())
    step('hostile_good')
    # Colours outside [0, 1] (NaN, 5, -3): skipped, named in the status.
    msg = hair_state()
    msg.strips[0].color.r = float('nan')
    msg.strips[1].color.g = 5.0
    msg.strips[2].color.b = -3.0
    send(msg)
    step('hostile_colour')
    # Control points near FLT_MAX (Ogre used to abort rviz on the mesh's bounding box) and 10,000 km away.
    msg = hair_state()
    msg.strips[0].xyz = [3.3e38 if k % 2 else -3.3e38 for k in range(len(msg.strips[0].xyz))]
    msg.strips[1].xyz = [v + 1e7 for v in msg.strips[1].xyz]
    send(msg)
    step('hostile_far_points')
    # One strip of 1000 x 1000 control points (8 million vertices at 2 x 4): over the budget, not drawn.
    msg = hair_state()
    big = msg.strips[0]
    big.columns = big.rows = 1000
    big.xyz = [0.0] * (3 * 1000 * 1000)
    for k in range(1000 * 1000):
        big.xyz[3 * k] = 1e-3 * (k % 1000)
        big.xyz[3 * k + 2] = 1.6 - 1e-3 * (k // 1000)
    send(msg)
    step('hostile_huge_grid')
    # 20,000 strips of 2 x 5 (3 x 17 = 51 vertices each at 2 x 4, 1.02 million in all): the last ones are not
    # drawn. Out of view (50 m down): software rendering of a million vertices on screen takes seconds a frame.
    msg = hair_state(20000, top=-50.0)
    send(msg)
    step('hostile_many_strips')
    send(hair_state())
    # A frame that tf does not know: rviz's tf filter drops the messages (when its queue of 10 overflows) and
    # says so in its Transform status; the last hair stays.
    msg = hair_state()
    msg.header.frame_id = 'nowhere'
    end = time.time() + 10.0
    while time.time() < end and not any('nowhere' in text for key, text in status().items()
                                        if key.startswith('Transform')):
        msg.header.stamp = rospy.Time.now()
        pub.publish(msg)
        run(0.05)
    step('hostile_unknown_frame')
    send(hair_state())  # the latched message is a good one again
    # Automatic level of detail with a huge Reference Distance: the highest level (8 x 16).
    auto = display.subProp('Auto Level of Detail')
    auto.subProp('Reference Distance').setValue(1e30)
    auto.setValue(True)
    step('hostile_auto_huge_reference')
    auto.setValue(False)
    auto.subProp('Reference Distance').setValue(1.0)
    # Unreliable (prefer UDP) with a rospy publisher, which has no UDP: TCP instead.
    display.subProp('Unreliable').setValue(True)
    wait_status('Topic', 'messages received', 10.0)
    step('hostile_unreliable')
    display.subProp('Unreliable').setValue(False)
    # A topic of another type, and no topic.
    topic.setValue('/rosout')
    wait_status('Topic', 'rosgraph_msgs/Log')
    step('hostile_wrong_type')
    topic.setValue('')
    step('hostile_empty_topic')
    # A publisher that goes away: the last hair stays, the status says nothing publishes the topic now.
    topic.setValue(GONE_TOPIC)
    publisher = subprocess.Popen(['/usr/bin/python3', os.path.realpath(__file__), '--publish', GONE_TOPIC])
    try:
        wait_status('Topic', 'messages received', 20.0)
        step('hostile_publisher')
    finally:
        publisher.terminate()
        publisher.wait()
    wait_status('Topic', 'nothing publishes')
    step('hostile_publisher_gone')


if __name__ == '__main__':
    if len(sys.argv) == 3 and sys.argv[1] == '--publish':
        publish(sys.argv[2])
        sys.exit(0)
    try:
        main()
    except Exception as e:  # reported to the test as JSON
        print(json.dumps({'error': '%s: %s' % (type(e).__name__, e)}))
        sys.stdout.flush()
        os._exit(1)
