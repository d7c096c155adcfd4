"""geofusion.core, the Python module (issue 35, docs/python.md): the demo recording fed keyframe by
keyframe through the module gives the map run_offline gives (ids, classes, poses to 1e-9), bad
input raises clear exceptions, the consistency score and the visual odometry answer from NumPy
arrays. Run by ctest python_module in the devel environment (pytest)."""
import os
import subprocess
import sys
import tempfile
import warnings

import numpy as np
import pytest
import yaml

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'ros'))
import geofusion_test_utils as util  # noqa: E402

gf = pytest.importorskip('geofusion.core')

KEYFRAMES = 30
K_DEMO = np.array([[554.254691191187, 0, 320.5], [0, 554.254691191187, 240.5], [0, 0, 1]])


def quaternion_matrix(q):
    """Rotation matrix of [qx, qy, qz, qw]."""
    x, y, z, w = np.asarray(q, float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def depth_metres(msg):
    """A sensor_msgs/Image of depth in metres, as the ROS layer converts it (depthToMetres)."""
    if msg.encoding == '32FC1':
        z = np.frombuffer(msg.data, '<f4').reshape(msg.height, msg.step // 4)[:, :msg.width]
    else:
        mm = np.frombuffer(msg.data, '<u2').reshape(msg.height, msg.step // 2)[:, :msg.width]
        z = mm.astype(np.float32) * np.float32(0.001)
    z = np.array(z, np.float32)
    z[~np.isfinite(z) | (z <= 0)] = 0
    return z


def recording_keyframes(bag_path, stamps):
    """The recording's frames at `stamps` as the module's inputs: depth, K, the odometry camera
    pose from the bag's TF (tf2, as run_offline looks it up) and the detections, all as read."""
    import rosbag
    import rospy
    import tf2_ros
    buffer = tf2_ros.Buffer(rospy.Duration(3600), debug=False)
    depth, info, dets = {}, {}, {}
    wanted = {round(s, 6) for s in stamps}
    with rosbag.Bag(bag_path) as bag, warnings.catch_warnings():
        warnings.simplefilter('ignore')  # tf2_ros on the bag's own message classes
        for topic, msg, _ in bag.read_messages():
            if topic in ('/tf', '/tf_static'):
                for t in msg.transforms:
                    (buffer.set_transform_static if topic == '/tf_static'
                     else buffer.set_transform)(t, 'bag')
                continue
            if not hasattr(msg, 'header') or round(msg.header.stamp.to_sec(), 6) not in wanted:
                continue
            key = round(msg.header.stamp.to_sec(), 6)
            if topic == '/head_camera/depth_registered/image_raw':
                depth[key] = msg
            elif topic == '/head_camera/rgb/camera_info':
                info[key] = msg
            elif topic == '/detections':
                dets[key] = msg
    frames = []
    for s in stamps:
        key = round(s, 6)
        d = dets[key]
        t = buffer.lookup_transform('odom', d.header.frame_id, d.header.stamp).transform
        pose = [t.translation.x, t.translation.y, t.translation.z,
                t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w]
        detections = [(x.class_name, x.score,
                       [x.pose.position.x, x.pose.position.y, x.pose.position.z,
                        x.pose.orientation.x, x.pose.orientation.y, x.pose.orientation.z,
                        x.pose.orientation.w]) for x in d.detections]
        K = np.array(info[key].K, float).reshape(3, 3)
        frames.append((depth_metres(depth[key]), K, pose, detections, d.header.stamp.to_sec()))
    return frames


@pytest.fixture(scope='module')
def demo():
    out = tempfile.mkdtemp(prefix='geofusion_python_')
    bag = util.generate_demo(out, KEYFRAMES)
    results = os.path.join(out, 'results.yaml')
    printed = subprocess.check_output([util.find_tool('run_offline'), '--bag', bag, '--out',
                                       results, '--quiet'], universal_newlines=True)
    with open(results) as f:
        return bag, yaml.safe_load(f), printed


def test_the_demo_through_the_module_is_run_offlines_map(demo):
    bag, expected, printed = demo
    stamps = [k['stamp'] for k in expected['keyframes']]
    assert len(stamps) >= KEYFRAMES - 1
    estimator = gf.SceneEstimator(gf.load_model_set('primitives'), gf.load_config())
    for depth, K, pose, detections, stamp in recording_keyframes(bag, stamps):
        r = estimator.add_keyframe(depth, K, pose, detections, stamp)
        assert len(r['detections']) == len(detections)
    final = estimator.finish()
    got = {o['id']: o for o in final['objects']}
    want = {o['id']: o for o in expected['final_map']['objects']}
    assert sorted(got) == sorted(want), 'object ids differ'
    assert len(want) >= 8
    for i, o in want.items():
        assert got[i]['class'] == o['class_name']
        p = o['map_object']
        np.testing.assert_allclose(got[i]['pose'][:3, 3], p[:3], rtol=0, atol=1e-9)
        np.testing.assert_allclose(got[i]['pose'][:3, :3], quaternion_matrix(p[3:]), rtol=0,
                                   atol=1e-9)
    assert len(final['trajectory']) == len(stamps)
    got_contacts = sorted((c['a'], c['b'], c['type'], c['kind'], c['distance_residual'])
                          for c in final['contacts'])
    want_contacts = sorted((c['a'], c['b'], c['type'], c['kind'], c['distance_residual'])
                           for c in expected['final_map']['contacts'])
    assert [c[:4] for c in got_contacts] == [c[:4] for c in want_contacts]
    np.testing.assert_allclose([c[4] for c in got_contacts], [c[4] for c in want_contacts],
                               rtol=0, atol=1e-9)
    # The same map under gravity: the module's check says what run_offline's summary says.
    stability = estimator.stability()
    assert sorted(o['id'] for o in stability['objects']) == sorted(want)
    assert stability['has_plane'] and not stability['warnings']
    assert stability['checked'] + stability['interpenetrating'] == len(want)
    assert all(np.isfinite(o['translation_m']) and o['stable'] == (
        not o['interpenetrating'] and o['translation_m'] < 0.005 and o['rotation_deg'] < 3.0)
        for o in stability['objects'])
    line = next(l for l in printed.splitlines() if l.startswith('run_offline: stability'))
    assert '%d of %d objects stable, %d more start interpenetrating' % (
        stability['stable'], stability['checked'], stability['interpenetrating']) in line, line
    # ... and its plan is the one in run_offline's results file, with the check's verdicts.
    graph = estimator.scene_graph()
    written = expected['final_map']['scene_graph']
    assert graph['removal_order'] == written['removal_order']
    assert sorted(graph['removal_order']) == sorted(want)
    by_id = {o['id']: o for o in written['objects']}
    verdict = {o['id']: o['stable'] for o in stability['objects']}
    for o in graph['objects']:
        w = by_id[o['id']]
        for key in ('supported_by', 'supports', 'leans_on', 'leaned_on_by', 'beside', 'over',
                    'covered_by', 'free_to_pick', 'removal_step'):
            assert o[key] == w[key], (o['id'], key)
        assert o['stable'] == verdict[o['id']] == bool(w['stable'])
        assert o['free_to_pick'] == (
            not o['supports'] and not o['leaned_on_by'] and not o['covered_by'])
    # The plan takes nothing before what rests, leans or lies on it.
    step = {i: graph['removal_order'].index(i) for i in graph['removal_order']}
    for o in graph['objects']:
        for above in o['supports'] + o['leaned_on_by'] + o['covered_by']:
            assert step[above] < step[o['id']], (above, o['id'])
    assert any(o['supports'] for o in graph['objects']), 'the demo has no stack'
    line = next(l for l in printed.splitlines() if l.startswith('run_offline: scene graph'))
    assert '%d of %d objects free to pick' % (
        sum(o['free_to_pick'] for o in graph['objects']), len(want)) in line, line


def test_a_keyframes_result_is_plain_python(demo):
    bag, expected, _ = demo
    estimator = gf.SceneEstimator(gf.load_model_set(), {'method': 'geofusion'})
    depth, K, pose, detections, stamp = recording_keyframes(
        bag, [expected['keyframes'][0]['stamp']])[0]
    r = estimator.add_keyframe(depth, K, pose, detections, stamp)
    assert r['keyframe'] == 0 and r['stamp'] == stamp
    assert r['T_map_cam'].shape == (4, 4)
    assert {d['decision'] for d in r['detections']} <= {
        'new_object', 'new_candidate', 'associated', 'candidate', 'removed', 'skipped'}
    assert all(0 <= d['consistency'] <= 1 for d in r['detections'] if d['consistency'] >= 0)
    assert r['timings_ms']['total'] > 0
    assert estimator.num_keyframes == 1 and estimator.method == 'GeoFusion'


def test_consistency_of_a_pose_against_a_depth_image():
    models = gf.load_model_set()
    depth = np.full((480, 640), 1.0, np.float32)  # a wall 1 m away
    in_front = gf.consistency(models, '005_tomato_soup_can', [0, 0, 0.9, 0, 0, 0, 1], depth,
                              K_DEMO)
    assert in_front['determined'] and in_front['r_out'] > 0.9 and in_front['score'] < 0.1
    behind = gf.consistency(models, '005_tomato_soup_can', [0, 0, 1.2, 0, 0, 0, 1], depth,
                            K_DEMO)
    assert behind['r_occ'] > 0.9


def textured_frame(seed=3):
    rng = np.random.default_rng(seed)
    grey = (rng.random((60, 80)) * 255).astype(np.uint8)
    grey = np.kron(grey, np.ones((8, 8), np.uint8))  # 480 x 640 blocks: corners to track
    return grey, np.full(grey.shape, 1.5, np.float32)


def test_visual_odometry_tracks_from_numpy():
    vo = gf.VisualOdometry(K_DEMO)
    grey, depth = textured_frame()
    first = vo.track(grey, depth)
    second = vo.track(grey, depth, stamp=0.033)
    assert first['pose_valid'] and second['pose_valid'], second['problem']
    assert second['state'] == 'tracking'
    assert np.abs(second['T_odom_cam'] - np.eye(4)).max() < 1e-3
    assert second['inliers'] >= 25
    assert second['by_depth'] is False
    # No texture, and the depth a bare wall: neither features nor the depth fallback can place it.
    bare = vo.track(np.full_like(grey, 128), depth, stamp=0.067)
    assert not bare['pose_valid'] and not bare['by_depth']
    assert 'direction free' in bare['problem'], bare['problem']
    with pytest.raises(ValueError, match='differ in size'):
        vo.track(grey, depth[:100], K_DEMO)
    with pytest.raises(TypeError, match='uint8'):
        vo.track(grey.astype(np.float32), depth, K_DEMO)
    with pytest.raises(ValueError, match='no camera matrix'):
        gf.VisualOdometry().track(grey, depth)


PRIMESENSE_D = [0.2312, -0.7849, -0.0033, -0.0001, 0.9172]  # docs/dataset.md, "lens"


def plumb_bob(K, D, u, v):
    """Where the lens puts the pinhole pixel (u, v) (the model written out, not OpenCV)."""
    k1, k2, p1, p2, k3 = D
    x, y = (u - K[0][2]) / K[0][0], (v - K[1][2]) / K[1][1]
    r2 = x * x + y * y
    radial = 1 + k1 * r2 + k2 * r2 ** 2 + k3 * r2 ** 3
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return K[0][0] * xd + K[0][2], K[1][1] * yd + K[1][2]


def test_rectify_makes_a_distorted_image_pinhole():
    K = np.array(K_DEMO, float)
    # A raw grey image with a bright 3 x 3 dot where the lens shows pinhole pixel (60, 50).
    du, dv = plumb_bob(K, PRIMESENSE_D, 60, 50)
    raw = np.zeros((480, 640), np.uint8)
    raw[int(round(dv)) - 1:int(round(dv)) + 2, int(round(du)) - 1:int(round(du)) + 2] = 255
    assert abs(du - 60) + abs(dv - 50) > 8  # the lens moves it by many pixels
    before = raw.copy()
    rect = gf.rectify(raw, K, PRIMESENSE_D)
    assert np.array_equal(raw, before)  # the caller's image as it was
    vs, us = np.nonzero(rect > 64)
    w = rect[vs, us].astype(float)
    # Its centre lands within a pixel of (60, 50) (the dot was placed to the nearest raw pixel).
    assert abs((us * w).sum() / w.sum() - 60) < 1.0 and abs((vs * w).sum() / w.sum() - 50) < 1.0
    # Depth takes the nearest pixel (no mixed depths); colour keeps its three channels.
    depth = np.where(np.arange(640)[None, :] < 100, 0.5, 1.2).astype(np.float32).repeat(480, 0)
    assert np.isin(gf.rectify(depth, K, PRIMESENSE_D), np.float32([0.0, 0.5, 1.2])).all()
    assert gf.rectify(np.zeros((480, 640, 3), np.uint8), K, PRIMESENSE_D).shape == (480, 640, 3)
    # No distortion: the same image.
    assert np.array_equal(gf.rectify(depth, K, [0, 0, 0, 0, 0]), depth)
    with pytest.raises(ValueError, match='coefficients'):
        gf.rectify(depth, K, [0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match='expected float32 H x W depth'):
        gf.rectify(depth.astype(np.float64), K, PRIMESENSE_D)


@pytest.fixture(scope='module')
def estimator():
    return gf.SceneEstimator(gf.load_model_set())


DEPTH = np.ones((48, 64), np.float32)
K_SMALL = np.array([[50.0, 0, 32], [0, 50.0, 24], [0, 0, 1]])
CAN = '005_tomato_soup_can'


@pytest.mark.parametrize('call, error, message', [
    (lambda e: e.add_keyframe(DEPTH.astype(np.float64), K_SMALL, np.eye(4), []), TypeError,
     'float32'),
    (lambda e: e.add_keyframe(DEPTH[0], K_SMALL, np.eye(4), []), ValueError, '2-D'),
    (lambda e: e.add_keyframe(DEPTH, np.eye(4), np.eye(4), []), ValueError, '3 x 3'),
    (lambda e: e.add_keyframe(DEPTH, K_SMALL, np.eye(3), []), ValueError, '4 x 4'),
    (lambda e: e.add_keyframe(DEPTH, K_SMALL, np.full((4, 4), np.nan), []), ValueError,
     'not finite'),
    (lambda e: e.add_keyframe(DEPTH, K_SMALL, 2 * np.eye(4), []), ValueError, 'not a rigid'),
    (lambda e: e.add_keyframe(DEPTH, K_SMALL, np.eye(4), [('nope', 0.9, np.eye(4))]),
     ValueError, "unknown class 'nope'"),
    (lambda e: e.add_keyframe(DEPTH, K_SMALL, np.eye(4),
                              [(CAN, 0.9, [np.nan, 0, 1, 0, 0, 0, 1])]), ValueError,
     'non-finite translation'),
    (lambda e: e.add_keyframe(DEPTH, K_SMALL, np.eye(4), [(CAN, 0.9, [0, 0, 1, 0, 0, 0, 2])]),
     ValueError, 'non-unit quaternion'),
    (lambda e: e.add_keyframe(DEPTH, K_SMALL, np.eye(4), [(CAN, 1.5, np.eye(4))]), ValueError,
     'score'),
    (lambda e: e.add_keyframe(DEPTH, K_SMALL, np.eye(4), [(CAN, 0.9)]), TypeError,
     r'\(class, score, pose\)'),
    (lambda e: e.add_keyframe(DEPTH, K_SMALL, np.eye(4), [(CAN, 0.9, 'pose')]), TypeError,
     'numbers'),
])
def test_bad_input_raises_a_clear_exception(estimator, call, error, message):
    with pytest.raises(error, match=message):
        call(estimator)
    assert estimator.num_keyframes == 0, 'a refused keyframe changed the estimator'


def test_configuration_errors_are_the_loaders():
    with pytest.raises(ValueError, match=r'association.eps_fp: expected a number in \[0.001, 1\]'):
        gf.load_config({'association': {'eps_fp': 7}})
    with pytest.warns(UserWarning, match='eps_fpp'):
        gf.load_config({'association': {'eps_fpp': 0.5}})
    with pytest.raises(ValueError, match='cannot'):
        gf.load_config('/nonexistent/params.yaml')
    with pytest.raises(TypeError):
        gf.load_config(42)
    assert 'eps_fp: 0.5' in gf.load_config({'association': {'eps_fp': 0.5}}).yaml(True)
    with pytest.raises(ValueError, match='model set'):
        gf.load_model_set('/nonexistent/models.yaml')


def test_depth_is_read_in_place_and_bad_values_count_as_no_depth(estimator):
    models = gf.load_model_set()
    depth = np.full((480, 640), 1.0, np.float32)
    with_holes = depth.copy()
    with_holes[:, :320] = np.nan
    a = gf.consistency(models, CAN, [0, 0, 0.9, 0, 0, 0, 1], depth, K_DEMO)
    b = gf.consistency(models, CAN, [0, 0, 0.9, 0, 0, 0, 1], with_holes, K_DEMO)
    assert b['missing'] > 0.3 * b['rendered'] and a['missing'] == 0
    assert np.isnan(with_holes[0, 0]), "the caller's array was changed"
