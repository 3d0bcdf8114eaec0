#!/usr/bin/python3
"""rostest node for hair_display.test (second test): rviz with the hair_sim/HairDisplay plugin under Xvfb,
against the real hair_sim_node following head_driver. Screenshots are read back with PIL/numpy.

The rviz config (test/hair_display.rviz) shows the HairDisplay alone (no markers, no head, no grid) on a
pure blue background B = (0, 0, 255). Hair is brown: every opaque hair pixel, however shaded (the texture
is grey, the Kajiya-Kay highlight white), has blue <= green. A pixel where partly transparent hair is
blended over the background has blue - green >= PARTIAL_MARGIN: the background shows through it. Hence:
  hair pixels     inside the render area (the bounding box of the background pixels), not background;
  partial pixels  hair pixels with blue - green >= PARTIAL_MARGIN (partly transparent hair over B);
  edge band       hair pixels 2 to EDGE_BAND px in from the hair's outline (4-neighbourhood distance to
                  the background). rviz draws with multisampling, so the outline pixel itself is a blend of
                  hair and background even for opaque strips: the band starts one pixel further in, where
                  only transparency lets the background through (soft strand edges, ragged tips).

  test_a_rviz_binary        `rviz -d test/hair_display.rviz` (the rviz executable). Once hair shows: hair
                            covers >= MIN_HAIR of the render area; the alpha texture shows: >= MIN_PARTIAL_EDGE
                            of the edge band and >= MIN_PARTIAL of the hair pixels are partial; the opaque
                            hair keeps the strips' colour from hair_state (red > green > blue, brown); the
                            hair moves: two shots MOTION_GAP s apart differ (by > 40 in a channel) on
                            >= MIN_MOTION of the hair pixels; the display's log line gives its update time
                            (tessellation, shading and upload per hair_state message), below MAX_UPDATE_MS.
  test_b_live_properties    rviz's VisualizationFrame in a child process (hair_display_live.py, python3-rviz)
                            with the same config; its display properties are changed while it runs:
                            Texture off: hair still there, partial pixels fall below MAX_PARTIAL_EDGE_OFF of the
                            edge band and MAX_PARTIAL_OFF of the hair (the negative control of the alpha check:
                            plain opaque strips have none but their multisampled outline); Alpha Threshold 0.6:
                            under 0.9 x the hair pixels at 0.05 (mean of the shots before and after: faint texels
                            dropped); Override
                            Colour red: the opaque hair turns red (red / green >= 3, the brown is < 2.5);
                            Level of Detail 0, 7, 3: Current Level 1 x 1 / 4 x 8 / 2 x 4 with the triangle
                            counts of the default hairstyle; Auto Level of Detail with the reference distance
                            at the view's distance: the camera 4 x farther gives a coarser level (<= 1 x 2),
                            2 x closer a finer one (>= 3 x 6); Topic elsewhere: no hair, Current Level "no
                            hair", the Topic status says nothing publishes it; back: hair.
  test_c_hostile_input      the hostile_* steps of the same run (messages from hair_display_live.py's own
                            publisher): strips with colours outside [0, 1] or control points beyond 1e6 m (near
                            FLT_MAX they made Ogre abort rviz) skipped and named; a 1000 x 1000 grid
                            and 20,000 strips held to the display's 1,000,000-vertex budget (exact counts, the
                            Vertices status); a frame tf does not know: named by rviz's tf filter, no
                            "Transform: OK" of the display's own beside it; Auto Level of Detail with Reference Distance 1e30: 8 x 16; Unreliable
                            with a publisher without UDP: messages still come; a topic of another type, no topic,
                            a publisher that goes away: each named in the Topic status, the last hair kept.

Screenshots and logs are kept in $ROS_HOME/hair_display_test/ (the build folder under ./run.sh test).
Arguments: the rviz config (test/hair_display.rviz).
"""
import json
import os
import re
import select
import signal
import subprocess
import sys
import tempfile
import time
import unittest

import numpy as np
import rostest
from PIL import Image

PKG = 'hair_sim'
NAME = 'hair_display_checks'

BACKGROUND = np.array([0, 0, 255], dtype=np.int16)
BACKGROUND_TOLERANCE = 3
PARTIAL_MARGIN = 12
MIN_HAIR = 0.03  # of the render area
EDGE_BAND = 4  # px
MIN_PARTIAL_EDGE = 0.3
MIN_PARTIAL = 0.1
MAX_PARTIAL_EDGE_OFF = 0.05
MAX_PARTIAL_OFF = 0.03
MIN_MOTION = 0.02
MOTION_GAP = 1.5  # s
MAX_UPDATE_MS = 33.0  # one frame at 30 Hz (the display typically takes 1 to 3 ms)
START_TIMEOUT = 60.0  # s: rviz start-up and the node's first messages
SCREEN = '1280x960x24'
# Default hairstyle: 100 strips of 2 x 5 control points; 2 (n_u - 1)(n_v - 1) triangles per strip.
LEVELS = {0: '1 x 1, 800 triangles', 3: '2 x 4, 6400 triangles', 7: '4 x 8, 25600 triangles'}


def out_dir():
    path = os.path.join(os.environ.get('ROS_HOME', tempfile.gettempdir()), 'hair_display_test')
    os.makedirs(path, exist_ok=True)
    return path


class VirtualScreen(object):
    """Xvfb on the first free display number (-displayfd)."""

    def __init__(self, log_path):
        read_fd, write_fd = os.pipe()
        self.log = open(log_path, 'w')
        self.process = subprocess.Popen(['Xvfb', '-displayfd', str(write_fd), '-screen', '0', SCREEN,
                                         '-nolisten', 'tcp'], pass_fds=(write_fd,), stdout=self.log,
                                        stderr=subprocess.STDOUT)
        os.close(write_fd)
        number = b''
        end = time.time() + 20.0
        while not number.endswith(b'\n') and time.time() < end:
            ready, _, _ = select.select([read_fd], [], [], 0.5)
            if ready:
                chunk = os.read(read_fd, 16)
                if not chunk:
                    break
                number += chunk
        os.close(read_fd)
        if not number.strip():
            self.close()
            raise RuntimeError('Xvfb did not start (see %s)' % log_path)
        self.display = ':' + number.decode().strip()

    def env(self):
        env = dict(os.environ)
        env['DISPLAY'] = self.display
        env['LIBGL_ALWAYS_SOFTWARE'] = '1'
        return env

    def screenshot(self, path):
        subprocess.run(['/usr/bin/import', '-display', self.display, '-window', 'root', path], check=True,
                       timeout=30, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        return path

    def close(self):
        stop(self.process)
        self.log.close()


def stop(process, timeout=10.0):
    if process.poll() is None:
        process.send_signal(signal.SIGINT)
        try:
            process.wait(timeout)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def load(png):
    return np.asarray(Image.open(png).convert('RGB')).astype(np.int16)


def render_area(image):
    """(rows, columns) slices of the render area: the bounding box of the background pixels, 2 px in."""
    background = np.abs(image - BACKGROUND).max(axis=2) <= BACKGROUND_TOLERANCE
    ys, xs = np.nonzero(background)
    if len(ys) < 10000:
        raise AssertionError('no render area with the background colour %s' % BACKGROUND.tolist())
    return slice(ys.min() + 2, ys.max() - 1), slice(xs.min() + 2, xs.max() - 1)


def analyse(png, area=None):
    image = load(png)
    rows, columns = area or render_area(image)
    image = image[rows, columns]
    background = np.abs(image - BACKGROUND).max(axis=2) <= BACKGROUND_TOLERANCE
    hair = ~background
    red, green, blue = image[..., 0], image[..., 1], image[..., 2]
    partial = hair & (blue - green >= PARTIAL_MARGIN)
    # Distance to the background in the 4-neighbourhood: rings[k] = pixels within k px of it.
    rings = [background]
    for _ in range(EDGE_BAND):
        grown = rings[-1].copy()
        grown[1:, :] |= rings[-1][:-1, :]
        grown[:-1, :] |= rings[-1][1:, :]
        grown[:, 1:] |= rings[-1][:, :-1]
        grown[:, :-1] |= rings[-1][:, 1:]
        rings.append(grown)
    edge = hair & rings[EDGE_BAND] & ~rings[1]
    opaque = hair & ~partial
    n_hair, n_edge, n_opaque = int(hair.sum()), int(edge.sum()), int(opaque.sum())
    return {
        'png': png, 'area': (rows, columns), 'image': image, 'hair_mask': hair,
        'hair': n_hair / float(hair.size),
        'partial': int(partial.sum()) / float(max(1, n_hair)),
        'partial_edge': int((partial & edge).sum()) / float(max(1, n_edge)),
        'mean_opaque': [float(c[opaque].mean()) if n_opaque else 0.0 for c in (red, green, blue)],
    }


def summary(a):
    return '%s: hair %.1f %% of the render area, partial %.1f %% of hair, %.1f %% of the edge band, opaque ' \
           'rgb %s' % (os.path.basename(a['png']), 100 * a['hair'], 100 * a['partial'], 100 * a['partial_edge'],
                       [round(c) for c in a['mean_opaque']])


class HairDisplayChecks(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        configs = [a for a in sys.argv[1:] if a.endswith('.rviz')]
        if not configs:
            raise RuntimeError('usage: hair_display_checks.py CONFIG.rviz')
        cls.config = configs[0]
        cls.dir = out_dir()
        cls.screen = VirtualScreen(os.path.join(cls.dir, 'xvfb.log'))

    @classmethod
    def tearDownClass(cls):
        cls.screen.close()

    def report(self, text):
        print('hair_display_checks: ' + text)
        sys.stdout.flush()

    def test_a_rviz_binary(self):
        log_path = os.path.join(self.dir, 'rviz.log')
        with open(log_path, 'w') as log:
            # Line-buffered: the display's log line must reach the file while rviz runs.
            rviz = subprocess.Popen(['stdbuf', '-oL', 'rviz', '-d', self.config], env=self.screen.env(),
                                    stdout=log, stderr=subprocess.STDOUT)
        try:
            # Wait until the hair shows.
            end = time.time() + START_TIMEOUT
            shot = os.path.join(self.dir, 'rviz_0.png')
            first = None
            while time.time() < end:
                time.sleep(1.0)
                self.assertIsNone(rviz.poll(), 'rviz exited (see %s)' % log_path)
                try:
                    first = analyse(self.screen.screenshot(shot))
                except AssertionError:  # no render area yet
                    continue
                if first['hair'] >= MIN_HAIR:
                    break
            self.assertIsNotNone(first, 'rviz showed no render area in %.0f s' % START_TIMEOUT)
            self.assertGreaterEqual(first['hair'], MIN_HAIR, 'no hair in %.0f s: %s' % (START_TIMEOUT,
                                                                                       summary(first)))
            time.sleep(1.0)
            a = analyse(self.screen.screenshot(os.path.join(self.dir, 'rviz_1.png')))
            time.sleep(MOTION_GAP)
            b = analyse(self.screen.screenshot(os.path.join(self.dir, 'rviz_2.png')), a['area'])
            self.report(summary(a))
            self.report(summary(b))
            for shot in (a, b):
                self.assertGreaterEqual(shot['hair'], MIN_HAIR, summary(shot))
                self.assertGreaterEqual(shot['partial_edge'], MIN_PARTIAL_EDGE, summary(shot))
                self.assertGreaterEqual(shot['partial'], MIN_PARTIAL, summary(shot))
                r, g, bl = shot['mean_opaque']
                self.assertTrue(r > g > bl, 'opaque hair is not brown: ' + summary(shot))
            changed = (np.abs(a['image'] - b['image']).max(axis=2) > 40) & (a['hair_mask'] | b['hair_mask'])
            motion = int(changed.sum()) / float(a['hair_mask'].sum())
            self.report('motion: %.1f %% of the hair pixels changed in %.1f s' % (100 * motion, MOTION_GAP))
            self.assertGreaterEqual(motion, MIN_MOTION, 'the hair did not move between rviz_1 and rviz_2')
            # The display logs its update time after 90 updates (3 s at 30 Hz).
            pattern = re.compile(r'hair_sim/HairDisplay: (.*): ([0-9.]+) ms (.*) per update')
            end = time.time() + 10.0
            match = None
            while match is None and time.time() < end:
                with open(log_path) as f:
                    match = pattern.search(f.read())
                time.sleep(0.5)
            self.assertIsNotNone(match, 'no update time line from HairDisplay in %s' % log_path)
            self.report('display update: %s: %s ms %s' % match.groups())
            self.assertLess(float(match.group(2)), MAX_UPDATE_MS)
        finally:
            stop(rviz)

    def test_b_live_properties(self):
        script = os.path.join(os.path.dirname(os.path.realpath(__file__)), 'hair_display_live.py')
        log_path = os.path.join(self.dir, 'rviz_live.log')
        with open(log_path, 'w') as log:
            live = subprocess.run(['/usr/bin/python3', script, self.config, self.dir], env=self.screen.env(),
                                  stdout=subprocess.PIPE, stderr=log, timeout=240)
        lines = live.stdout.decode(errors='replace').strip().splitlines()
        with open(log_path, 'a') as log:
            log.write('\n'.join(lines))
        self.assertTrue(lines, 'hair_display_live.py printed nothing, exit status %d (see %s)' %
                        (live.returncode, log_path))
        try:
            result = json.loads(lines[-1])
        except ValueError:
            self.fail('hair_display_live.py ended without its JSON line, exit status %d (a crash?): see %s' %
                      (live.returncode, log_path))
        self.assertNotIn('error', result, result.get('error'))
        steps = {s['name']: s for s in result['steps']}
        type(self).live_steps = steps  # for test_c_hostile_input
        area = render_area(load(steps['textured']['png']))
        shots = {name: analyse(s['png'], area) for name, s in steps.items()}
        for name in ('textured', 'untextured', 'threshold_0.6', 'override_red', 'topic_back', 'other_topic'):
            self.report(summary(shots[name]))
        self.report('update time: ' + steps['textured']['update_time'])

        textured, untextured = shots['textured'], shots['untextured']
        self.assertGreaterEqual(textured['partial_edge'], MIN_PARTIAL_EDGE, summary(textured))
        self.assertGreaterEqual(untextured['hair'], MIN_HAIR, summary(untextured))
        self.assertLessEqual(untextured['partial_edge'], MAX_PARTIAL_EDGE_OFF, summary(untextured))
        self.assertLessEqual(untextured['partial'], MAX_PARTIAL_OFF, summary(untextured))

        # The hair moves meanwhile: compare with the mean of the shots just before and after.
        around = 0.5 * (textured['hair'] + shots['override_red']['hair'])
        self.assertLess(shots['threshold_0.6']['hair'], 0.9 * around, summary(shots['threshold_0.6']))

        r, g, _ = textured['mean_opaque']
        self.assertLess(r / max(g, 1.0), 2.5, summary(textured))
        r, g, _ = shots['override_red']['mean_opaque']
        self.assertGreaterEqual(r / max(g, 1.0), 3.0, summary(shots['override_red']))

        for level, text in LEVELS.items():
            self.assertEqual(steps['level_%d' % level]['current_level'], text)

        def samples(step):
            across, along = re.match(r'(\d+) x (\d+),', steps[step]['current_level']).groups()
            return int(across), int(along)

        self.report('auto level of detail: reference %s, 4 x farther %s, 2 x closer %s' %
                    tuple(steps[s]['current_level'] for s in ('auto_reference', 'auto_far', 'auto_near')))
        self.assertLessEqual(samples('auto_far')[1], 2)
        self.assertGreaterEqual(samples('auto_near')[1], 6)
        self.assertLess(samples('auto_far')[1], samples('auto_reference')[1])
        self.assertLess(samples('auto_reference')[1], samples('auto_near')[1])

        self.assertLess(shots['other_topic']['hair'], 0.001, summary(shots['other_topic']))
        # The read-only level no longer claims the triangles of hair it cleared, and the status says why.
        self.assertEqual(steps['other_topic']['current_level'], 'no hair')
        self.assertIn('nothing publishes /no_hair_here', steps['other_topic']['status'].get('Topic', ''))
        self.assertGreaterEqual(shots['topic_back']['hair'], MIN_HAIR, summary(shots['topic_back']))

    def test_c_hostile_input(self):
        """The hostile_* steps of hair_display_live.py (run by test_b): the display's status and level."""
        steps = getattr(type(self), 'live_steps', None)
        self.assertIsNotNone(steps, 'test_b_live_properties did not get the live steps')
        for name in sorted(steps):
            if name.startswith('hostile'):
                self.report('%s: %s; %s' % (name, steps[name]['current_level'], steps[name]['status']))
        misses = []  # every check is made, and every miss listed

        def expect(name, key, wanted, exact=False):
            """Step name's status entry key (or 'current_level') contains (or with exact, equals) wanted."""
            got = steps[name]['current_level'] if key == 'current_level' else steps[name]['status'].get(key, '')
            if (got != wanted) if exact else (wanted not in got):
                misses.append('%s: %s is %r, expected %s%r' % (name, key, got, '' if exact else 'to contain ',
                                                               wanted))

        # 20 synthetic strips of 2 x 5 control points: 3 x 17 vertices and 64 triangles each at 2 x 4.
        # The first message of the new topic is counted as the first (not after /hair_state's last few).
        expect('hostile_good', 'Topic', '1 messages received', True)
        expect('hostile_good', 'Strips', '20 strips', True)
        expect('hostile_good', 'Vertices', '', True)
        expect('hostile_good', 'current_level', '2 x 4, 1280 triangles', True)
        # Colours NaN, 5 and -3: those strips are skipped, the first named.
        expect('hostile_colour', 'Strips', '3 of 20 strips skipped; strip 0: colour (nan, ')
        expect('hostile_colour', 'current_level', '2 x 4, 1088 triangles', True)
        # Control points near FLT_MAX and 1e7 m away: skipped (rviz used to abort), the first named.
        expect('hostile_far_points', 'Strips',
               '2 of 20 strips skipped; strip 0: control point 0 (-3.3e+38, 3.3e+38, -3.3e+38) is more than 1e+06 m')
        expect('hostile_far_points', 'current_level', '2 x 4, 1152 triangles', True)
        # A 1000 x 1000 grid (8 million vertices at 2 x 4) is over the vertex budget: the other 19 are drawn.
        expect('hostile_huge_grid', 'Strips', '19 strips', True)
        expect('hostile_huge_grid', 'Vertices', '1 strips not drawn (from strip 0 on)')
        expect('hostile_huge_grid', 'current_level', '2 x 4, 1216 triangles', True)
        # 20,000 strips of 51 vertices: 19,607 fit in 1,000,000 vertices.
        expect('hostile_many_strips', 'Strips', '19607 strips', True)
        expect('hostile_many_strips', 'Vertices', '393 strips not drawn (from strip 19607 on)')
        expect('hostile_many_strips', 'current_level', '2 x 4, %d triangles' % (19607 * 64), True)
        # A frame tf does not know: rviz's tf filter names it; no "Transform: OK" of the display's own beside
        # that error; the last hair stays.
        unknown = steps['hostile_unknown_frame']['status']
        if not any('nowhere' in text for key, text in unknown.items() if key.startswith('Transform')):
            misses.append('hostile_unknown_frame: no Transform status names the frame: %s' % unknown)
        expect('hostile_unknown_frame', 'Transform', '', True)
        expect('hostile_unknown_frame', 'current_level', '2 x 4, 1280 triangles', True)
        # Reference Distance 1e30 m: the highest level, not the lowest.
        expect('hostile_auto_huge_reference', 'current_level', '8 x 16, 20480 triangles', True)
        # Unreliable with a publisher that has no UDP (rospy): the messages come over TCP.
        expect('hostile_unreliable', 'Topic', 'messages received')
        expect('hostile_unreliable', 'Strips', '20 strips', True)
        expect('hostile_wrong_type', 'Topic', '/rosout is published as rosgraph_msgs/Log, not hair_sim_msgs/HairState')
        expect('hostile_empty_topic', 'Topic', 'No topic set', True)
        # A publisher that goes away: its last hair stays, the status says that nothing publishes now.
        expect('hostile_publisher', 'Topic', 'messages received')
        expect('hostile_publisher_gone', 'Topic', 'nothing publishes /hair_display_gone now')
        expect('hostile_publisher_gone', 'current_level', '2 x 4, 1280 triangles', True)
        gone = analyse(steps['hostile_publisher_gone']['png'], render_area(load(steps['textured']['png'])))
        self.report(summary(gone))
        if gone['hair'] < 0.01:
            misses.append('hostile_publisher_gone: no hair on screen: ' + summary(gone))
        self.assertFalse(misses, '%d misses:\n' % len(misses) + '\n'.join(misses))


if __name__ == '__main__':
    rostest.rosrun(PKG, NAME, HairDisplayChecks, sys.argv)
