"""Every command the README and the docs/ pages show is exercised by a test: the commands
are read out of README.md and docs/*.md (code blocks and inline code) and each must be listed
here with the test that runs it, and that test must exist. A command added to a page without
a test fails this. The README stays a front page: short, linking every docs page, and no
link between the pages points at a file or heading that is not there."""
import glob
import os
import re

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
README = os.path.join(ROOT, 'README.md')
DOCS = os.path.join(ROOT, 'docs')
README_MAX_LINES = 250
PREFIX = re.compile(r'(?:\./env\.sh |sudo )?(?:roslaunch|rosrun|rostest|python3? -m|make|'
                    r'catkin_make|catkin|catkin_lint|git clone|pip install|apt-get|source)(?=\s|$)')

SMOKE = 'test_launch_smoke.py::test_launch_reaches_its_purpose'
WORKSPACE = 'test_catkin_workspace.py::test_builds_tests_installs_and_runs_in_a_users_workspace'
# Documented command (after `cd ... &&`, without comments) -> test file::function that runs it.
COVERED = {
    './env.sh python -m pytest test/test_arm_teleop.py': 'test_arm_teleop.py',
    './env.sh roslaunch leap_teleop ardrone.launch': 'drone_flight.test',
    # the demo's arm half, with the same defaults (test_launch_smoke.py checks that)
    './env.sh roslaunch leap_teleop ur10_dual.launch': 'test_demo.py::test_demo_succeeds_and_writes_its_outputs',
    './env.sh rosrun leap_teleop sender.py --help': 'test_scripts.py::test_rosrun_script_help',
    'rosrun leap_teleop sender.py --help': 'test_scripts.py::test_rosrun_script_help',
    "./env.sh python -m leap_teleop.hands.classify_frames 'photos/*.jpg'":
        'test_camera_source.py::test_classify_frames_reads_images_and_videos',
    './env.sh roslaunch leap_teleop ur10_dual.launch source:=video video:=clip.mp4 '
    'annotated_image_topic:=/camera/annotated': 'camera_video_ur10.test',
    'rosrun leap_teleop NODE --help': 'test_scripts.py::test_rosrun_script_help',
    'rosrun leap_teleop classify_frames': 'test_scripts.py::test_rosrun_script_help',
    './env.sh rostest leap_teleop sender.test': 'test_rostests.py::test_rostest',
    'rosrun dynamic_reconfigure dynparam set /ur10_1/ur10_arm max_joint_speed 0.02':
        'test_reconfigure.py::test_dynparam_retunes_the_arm_and_cannot_disable_its_speed_limit',
    'roslaunch leap_teleop leap_motion.launch source:=recording recording:=FILE':
        'test_driver_interface.py::test_a_recording_reaches_a_driver_consumer',
    'catkin build': WORKSPACE,
    'catkin_lint -W2 --strict': WORKSPACE,
    'catkin_make': WORKSPACE,
    'catkin_make -DPYTHON_EXECUTABLE=$(which python)': WORKSPACE,     # the venv's, as it does
    'catkin_make install': WORKSPACE,
    'catkin_make run_tests': WORKSPACE,
    'git clone <this repository> leap_teleop': WORKSPACE,     # a copy of the tracked files
    'source devel/setup.bash': WORKSPACE,
    'make demo': 'test_demo.py::test_demo_succeeds_and_writes_its_outputs',
    'make eval': 'test_eval_gestures.py::test_main_writes_the_json',
    './env.sh python -m tools.latency_overlay_snapshot docs/camera_latency.png':
        'test_latency_overlay_snapshot.py::test_the_command_writes_the_overlay_picture',
    './env.sh rosrun leap_teleop latency_monitor':
        'test_latency_monitor.py::test_the_command_prints_the_pilots_row_from_a_running_node',
    'make check': 'test_make_targets.py::test_make_check_runs_the_unit_tests_only',
    'make lint': 'test_make_targets.py::test_make_lint_is_clean',
    './env.sh python -m tools.evaluation.strokes --loso':
        'test_eval_strokes.py::test_loso_command_meets_the_goals',
    './env.sh python -m tools.evaluation.photo_views':
        'test_photo_views.py::test_main_prints_and_writes_the_table',
    'make bench': 'test_bench_ros_processes.py::test_each_run_writes_a_fresh_file',
    './env.sh python -m leap_teleop.hands.classify_frames --keypoints '
    '../shared/data/keypoints/Harikumar4.csv':
        'test_classify_frames.py::test_keypoints_in_both_csv_forms_give_one_line_per_row',
    './env.sh python -m leap_teleop.hands.classify_frames --stateless '
    '../shared/data/leap_people/gti_dev.jsonl.gz': 'test_classify_frames.py::test_the_shared_people_files_classify',
    'make train': 'test_people_eval.py::test_train_command_writes_a_model_and_its_card',
    'python -m tools.evaluation.people':
        'test_people_eval.py::test_evaluate_people_command_writes_its_figures',
    'roslaunch leap_teleop sender.launch source:=leap gesture_model:=$HOME/two.npz '
    'gesture_bindings:=$HOME/mine.yaml': 'test_own_gestures.py::test_the_nodes_arm_on_a_bound_new_gesture',
    'rosrun leap_teleop classify_frames two.jsonl --stateless --model ~/two.npz':
        'test_own_gestures.py::test_classify_frames_reports_the_new_gesture',
    'rosrun leap_teleop record_gestures --source leap --label two --seconds 10':
        'test_own_gestures.py::test_record_gestures_from_a_leap_recording',
    'rosrun leap_teleop record_gestures --source webcam --label peace --seconds 10':
        'test_own_gestures.py::test_camera_hands_become_community_normalised_keypoint_rows',
    'rosrun leap_teleop train_gestures --add two.jsonl --label two --out ~/two.npz':
        'test_own_gestures.py::test_default_retrain_includes_the_leave_one_person_out_report',
    'python -m leap_teleop.hands.classify_frames':
        'test_classify_frames.py::test_json_lines_on_stdin_stream_and_stateless',
    'python -m tools.make_sessions': 'test_arm_closed_loop.py',
    # make demo runs rotated_task.run, which the module's main() calls.
    'python -m tools.rotated_task': 'test_demo.py::test_demo_succeeds_and_writes_its_outputs',
    'python -m tools.param_table --write docs/nodes.md':
        'test_param_table.py::test_write_regenerates_a_stale_copy_and_keeps_the_rest',
    'python -m leap_teleop.ros.recording_to_bag --script config/gestures/ur10_pick_place_dual.yaml '
    '/tmp/dual.bag': 'test_bag_tools.py::test_to_bag_writes_a_scripted_session',
    'rosrun leap_teleop recording_to_bag ../shared/data/leapjs/grab.json.lz /tmp/grab.bag':
        'test_bag_tools.py::test_recording_to_bag_writes_the_take',
    'roslaunch leap_teleop ardrone.launch sim:=false': SMOKE,
    'roslaunch leap_teleop record.launch':
        'test_launch_smoke.py::test_documented_arg_values_parse',
    'roslaunch leap_teleop record.launch output:=/tmp/session.bag':
        'test_launch_smoke.py::test_record_launch_records_a_running_sender',
    'roslaunch leap_teleop replay.launch bag:=/tmp/session.bag '
    'topics:="/leapmotion/data_right /leapmotion/data_left"':
        'test_record_replay.py::test_recorded_drone_session_replays_into_the_pilot',
    'roslaunch leap_teleop replay.launch bag:=one_arm.bag topics:=/leapmotion/data':
        'test_replay_remap.py::test_original_bag_replays_into_the_single_arm',
    'roslaunch leap_teleop replay.launch bag:=two_arm.bag topics:=/leapmotion/data_right '
    'remap_from:=/leapmotion/data_right remap_to:=/leapmotion/data':
        'test_replay_remap.py::test_original_bag_replays_into_the_single_arm',
    'roslaunch leap_teleop sender.launch leapros_topic:=leapmotion/data': 'leapros.test',
    'roslaunch leap_teleop sender.launch source:=recording recording:=PATH':
        'test_launch_smoke.py::test_sender_launch_plays_a_recording',
    'roslaunch leap_teleop ur10_dual.launch rviz:=true':
        'test_launch_smoke.py::test_documented_arg_values_parse',
    'roslaunch leap_teleop ur10_dual.launch sender:=false': 'ur10_teleop_dual.test',
    'source env.sh': 'test_network_exposure.py',
}
# Run by CI itself (.ci/run: make test = make setup, then pytest test/), not by a test.
BY_CI = {'make test', 'make setup',
         'pip install -r leap_teleop/tools/requirements.txt',
         'pip install --no-deps -r leap_teleop/tools/requirements-camera.txt',
         "sudo apt-get install $(grep -vE '^\\s*(#|$)' leap_teleop/tools/debian-packages.txt)"}
# Not run by any test, and why.
NOT_RUN = {
    'make soak': '20 wall minutes; the integrator runs it',
    'python -m tools.soak --burst-minutes 3': 'make soak with a load burst (~26 wall '
        'minutes); test_bench_ros_processes.py checks its options and results file',
    'python -m tools.soak --minutes 4 --burst-minutes 1': 'a shorter soak with a load burst '
        '(~4 wall minutes of the full graph beside CPU hogs); test_bench_ros_processes.py '
        'checks its options and results file',
    'python -m tools.soak --minutes 5 --burst-minutes 1': 'the same, five simulated minutes '
        '(~6 wall minutes); test_bench_ros_processes.py checks its options and results file',
    'python -m tools.soak --minutes 4 --burst-minutes 1 --hand-queue 50': 'the same with the '
        'consumers\' hand queue named (the reliability page\'s series)',
    'make loaded': 'the demo and every rostest again, beside two CPU hogs (~15 wall '
        'minutes); the integrator runs it, test_under_load.py checks tools.under_load',
    'python -m tools.under_load --hogs 2 -- make demo': 'part of make loaded; '
        'test_under_load.py runs tools.under_load with a measuring command',
    'python -m tools.bench --only arm_motion': 'a benchmark, part of make bench (the '
        'integrator runs it); test_bench_ros_processes.py checks the bench runner itself',
    'python -m tools.lag_tradeoff': 'tens of minutes of closed-loop runs (a measurement '
        'for the docs); test_arm_real_motion.py runs its real-motion figures on one take',
    'make demo GUI=1': 'needs a display; make demo runs headless in test_demo.py',
    'make clean': 'deletes the build the other tests use',
    'rosrun leap_teleop record_frames my_take.json.gz --source leap': 'needs a Leap device; '
        'record_frames with the scripted source is in test_sources_recording.py',
    './env.sh roslaunch leap_teleop ur10_dual.launch source:=webcam': 'needs a webcam; the '
        'video source through the same launch is camera_video_ur10.test',
    './env.sh roslaunch leap_teleop ardrone.launch source:=webcam device:=/dev/video2 '
    'mirror:=true': 'needs a webcam; the video source through ardrone.launch is '
        'camera_video_drone.test',
}


def pages():
    """README.md and every docs/*.md page: {path: text}."""
    paths = [README] + sorted(glob.glob(os.path.join(DOCS, '*.md')))
    out = {}
    for path in paths:
        with open(path) as f:
            out[path] = f.read()
    return out


def documented_commands():
    found = set()
    for text in pages().values():
        for block in re.findall(r'```bash\n(.*?)```', text, re.S):
            block = re.sub(r'\\\n\s*', '', block)          # continued lines
            for line in block.splitlines():
                line = line.split(' #')[0].strip()
                line = re.sub(r'^cd [^&]+&& ', '', line)
                if PREFIX.match(line):
                    found.add(line)
        for inline in re.findall(r'`([^`\n]+)`', text):
            if PREFIX.match(inline):
                found.add(inline.strip())
    return found


def test_every_documented_command_has_a_test():
    missing = sorted(documented_commands() - set(COVERED) - BY_CI - set(NOT_RUN))
    assert not missing, 'documented commands without a test (add one, list it in COVERED):\n' + \
        '\n'.join(missing)


def test_the_listed_tests_exist():
    for command, where in COVERED.items():
        path, _, func = where.partition('::')
        text = open(os.path.join(HERE, path)).read()
        assert not func or re.search(r'def %s\(' % re.escape(func), text), (command, where)


def test_the_lists_hold_only_documented_commands():
    stale = (set(COVERED) | BY_CI | set(NOT_RUN)) - documented_commands()
    assert not stale, sorted(stale)


def test_the_readme_is_a_front_page_linking_every_docs_page():
    text = pages()[README]
    assert len(text.splitlines()) <= README_MAX_LINES, len(text.splitlines())
    linked = set(re.findall(r'\]\(docs/([^)#]+\.md)(?:#[^)]*)?\)', text))
    docs = {os.path.basename(p) for p in glob.glob(os.path.join(DOCS, '*.md'))}
    assert docs and not docs - linked, sorted(docs - linked)


def anchor(heading):
    """GitHub's anchor for a Markdown heading."""
    return re.sub(r'[^\w\- ]', '', heading.strip().lower()).replace(' ', '-')


def test_links_between_the_pages_reach_a_file_and_heading():
    texts = pages()
    for path, text in texts.items():
        text = re.sub(r'```.*?```', '', text, flags=re.S)
        for target in re.findall(r'\]\(([^)\s]+)\)', text):
            if re.match(r'[a-z]+://', target):
                continue
            file_part, _, fragment = target.partition('#')
            dest = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) \
                if file_part else path
            assert os.path.exists(dest), (path, target)
            if fragment:
                with open(dest) as f:
                    headings = re.findall(r'^#+ (.+)$', re.sub(r'```.*?```', '', f.read(),
                                                                  flags=re.S), re.M)
                assert fragment in {anchor(h) for h in headings}, (path, target)


def test_the_troubleshooting_quotes_the_lines_a_missing_sdk_prints():
    # It quoted a line a missing SDK never prints, so a search for the printed one failed.
    from leap_teleop.hands.sources import leap_sdk, leapc
    readme = open(os.path.join(ROOT, 'README.md')).read()
    for hint in (leap_sdk.INSTALL_HINT, leapc.INSTALL_HINT):
        quoted = hint.split(' (import')[0]
        assert ' '.join(quoted.split()) in ' '.join(readme.split()), quoted
