# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The offline command end to end on small inputs the tests write."""

import json
import os
import sys
import threading

from bags import write_image_bag
import cv2
from dgmod_ros import cli, config
from dgmod_ros.core.metrics import iou
from dgmod_ros.core.runtime import IO_THREAD_NICENESS
from dgmod_ros.core.synthetic import synthetic_scene
import numpy as np
import pytest

SHAPE = (72, 96)


@pytest.fixture(scope='module')
def scene():
    return synthetic_scene(n_frames=30, shape=SHAPE, seed=11)


def write_folder(folder, frames, cdnet=False):
    root = folder / 'input' if cdnet else folder
    root.mkdir(parents=True)
    for index, frame in enumerate(frames):
        cv2.imwrite(str(root / f'in{index + 1:06d}.png'), cv2.cvtColor(frame, cv2.COLOR_RGB2BGR))
    return folder


def run(*argv):
    return cli.main([str(a) for a in argv] + ['--quiet'])


def check_outputs(out, scene, stems, mode, method='dgmod'):
    report = json.loads((out / 'report.json').read_text())
    assert report['method'] == method and report['mode'] == mode
    assert report['frames'] == len(stems) and report['fps'] > 0
    assert report['parameters']['window'] == 20
    assert report['windows'] and all({'seconds', 'iterations'} <= set(w)
                                     for w in report['windows'])
    masks = sorted((out / 'masks').iterdir())
    assert [p.stem for p in masks] == stems
    images = [cv2.imread(str(p), cv2.IMREAD_GRAYSCALE) for p in masks]
    assert all(m.shape == SHAPE and set(np.unique(m)) <= {0, 255} for m in images)
    assert len(list((out / 'background').iterdir())) >= len(report['windows'])
    # Measured: mean IoU 0.88 on frames 20-29 of this scene for every input kind and mode.
    return np.mean([iou(m, scene.masks[i]) for i, m in enumerate(images) if i >= 20])


@pytest.mark.parametrize('mode', ['stream', 'batch'])
def test_folder_round_trip(tmp_path, scene, mode):
    folder = write_folder(tmp_path / 'seq', scene.frames, cdnet=True)
    out = tmp_path / 'out'
    assert run('separate', folder, '--out', out, '--mode', mode, '--window', 20,
               '--stride', 5) == 0
    stems = [f'in{i + 1:06d}' for i in range(len(scene.frames))]
    assert check_outputs(out, scene, stems, mode) > 0.75


def test_video_round_trip(tmp_path, scene):
    video = tmp_path / 'clip.avi'
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*'MJPG'), 30, SHAPE[::-1])
    assert writer.isOpened()
    for frame in scene.frames:
        writer.write(cv2.cvtColor(frame, cv2.COLOR_RGB2BGR))
    writer.release()
    out = tmp_path / 'out'
    assert run('separate', video, '--out', out, '--window', 20, '--stride', 5) == 0
    assert check_outputs(out, scene, [f'{i:06d}' for i in range(30)], 'stream') > 0.75


@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_rosbag_round_trip(tmp_path, scene, storage):
    bag = write_image_bag(tmp_path / 'bag', scene.frames, storage=storage)
    out = tmp_path / 'out'
    assert run('separate', bag, '--out', out, '--window', 20, '--stride', 5,
               '--method', 'median') == 0
    assert check_outputs(out, scene, [f'{i:06d}' for i in range(30)], 'stream', 'median') > 0.75


def test_bag_with_two_image_topics_needs_topic(tmp_path, scene, capsys):
    bag = write_image_bag(tmp_path / 'bag', scene.frames[:5])
    out = tmp_path / 'out'
    assert run('separate', bag, '--out', out, '--topic', '/other') == 2
    assert 'no sensor_msgs/msg/Image topic' in capsys.readouterr().err
    assert not out.exists()


def test_config_file_and_options_combine(tmp_path, scene):
    folder = write_folder(tmp_path / 'seq', scene.frames[:12])
    params = tmp_path / 'p.yaml'
    params.write_text('/detector:\n  ros__parameters:\n    window: 10\n    stride: 4\n'
                      '    mask_threshold: 0.2\n')
    out = tmp_path / 'out'
    assert run('separate', folder, '--out', out, '--config', params, '--stride', 5) == 0
    parameters = json.loads((out / 'report.json').read_text())['parameters']
    assert (parameters['window'], parameters['stride'], parameters['mask_threshold']) == \
        (10, 5, 0.2)


def test_invalid_parameters_are_one_clear_error(tmp_path, scene, capsys):
    folder = write_folder(tmp_path / 'seq', scene.frames[:5])
    assert run('separate', folder, '--out', tmp_path / 'o', '--window', 5, '--stride', 9) == 2
    err = capsys.readouterr().err
    assert err.startswith('dgmod: error: stride must be') and err.count('\n') == 1


def test_corrupt_image_stops_with_one_sentence_and_no_output(tmp_path, scene, capsys):
    folder = write_folder(tmp_path / 'seq', scene.frames[:12])
    (folder / 'in000005.png').write_bytes(b'not a png at all')
    out = tmp_path / 'out'
    assert run('separate', folder, '--out', out) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith('dgmod: error: cannot decode image') and 'in000005' in err[-1]
    assert not out.exists() and not (tmp_path / 'out.partial').exists()


def test_skip_bad_skips_and_reports(tmp_path, scene):
    folder = write_folder(tmp_path / 'seq', scene.frames[:12])
    (folder / 'in000005.png').write_bytes(b'not a png at all')
    cv2.imwrite(str(folder / 'in000009.png'), np.zeros((10, 10, 3), np.uint8))
    out = tmp_path / 'out'
    assert run('separate', folder, '--out', out, '--skip-bad', '--window', 5,
               '--stride', 5) == 0
    report = json.loads((out / 'report.json').read_text())
    assert report['frames'] == 10 and len(report['skipped']) == 2
    assert any('in000009' in str(s['frame']) for s in report['skipped'])
    assert len(list((out / 'masks').iterdir())) == 10


def test_mixed_sizes_stop_unless_skipped(tmp_path, scene, capsys):
    folder = write_folder(tmp_path / 'seq', scene.frames[:8])
    cv2.imwrite(str(folder / 'in000009.png'), np.zeros((10, 10, 3), np.uint8))
    assert run('separate', folder, '--out', tmp_path / 'out') == 2
    assert 'is 10 x 10, the sequence started at 96 x 72' in capsys.readouterr().err
    assert not (tmp_path / 'out').exists()


def test_unreadable_bag_is_one_clear_error(tmp_path, capsys):
    bag = tmp_path / 'broken.mcap'
    bag.write_bytes(b'\x89MCAP0\r\n' + bytes(100))
    assert run('separate', bag, '--out', tmp_path / 'out') == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith('dgmod: error:') and 'broken.mcap' in err[0]
    assert not (tmp_path / 'out').exists()


def test_existing_output_is_not_overwritten_without_force(tmp_path, scene, capsys):
    folder = write_folder(tmp_path / 'seq', scene.frames[:6])
    out = tmp_path / 'out'
    out.mkdir()
    assert run('separate', folder, '--out', out) == 2
    assert 'exists' in capsys.readouterr().err


# Every boolean option of both commands, from the table: a new one is covered by itself.
BOOLEANS = [(command, spec.name) for command in ('separate', 'evaluate')
            for spec in cli.offline_parameters(command) if isinstance(spec.default, bool)]
TRUE_FORMS = [[], ['true'], ['True'], ['yes'], ['on'], ['1']]
FALSE_FORMS = [['false'], ['FALSE'], ['no'], ['off'], ['0']]


def parse(command, *options):
    head = ['separate', 'input'] if command == 'separate' else ['evaluate', 'dataset']
    return cli.build_parser().parse_args(head + ['--out', 'out'] + list(options))


def test_the_boolean_table_is_every_boolean_offline_parameter():
    offline = {spec.name for spec in config.PARAMETERS
               if isinstance(spec.default, bool) and spec.where != 'node'}
    assert offline and {name for _, name in BOOLEANS} == offline
    assert {command for command, _ in BOOLEANS} == {'separate', 'evaluate'}


@pytest.mark.parametrize('command, name', BOOLEANS)
def test_boolean_options_take_what_a_user_types(command, name):
    option = cli.option_name(name)
    assert cli.resolve_parameters(parse(command))[0][name] is config.DEFAULTS[name]
    for words, expected in [(w, True) for w in TRUE_FORMS] + [(w, False) for w in FALSE_FORMS]:
        for argv in ([option] + words, [f'{option}={words[0]}'] if words else [option]):
            values, given = cli.resolve_parameters(parse(command, *argv))
            assert values[name] is expected, argv
            assert given[name] == option
    assert cli.resolve_parameters(parse(command, '--no-' + option[2:]))[0][name] is False
    # The last one given wins, as for any option.
    assert cli.resolve_parameters(parse(command, option, 'no', option))[0][name] is True


@pytest.mark.parametrize('command, name', BOOLEANS)
@pytest.mark.parametrize('word', ['maybe', 'flase', '2', ''])
def test_anything_else_is_refused_in_one_line(command, name, word, capsys):
    option = cli.option_name(name)
    with pytest.raises(SystemExit) as stop:
        parse(command, f'{option}={word}')
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and option in err and repr(word) in err
    assert err.startswith(f'dgmod {command}: error: argument {option}: expected true or false')


def test_a_boolean_given_false_runs_false_end_to_end(tmp_path, scene):
    folder = write_folder(tmp_path / 'seq', scene.frames[:8])
    assert run('separate', folder, '--out', tmp_path / 'out', '--window', 5, '--stride', 5,
               '--conditional-update', 'false', '--no-ghost-test') == 0
    parameters = json.loads((tmp_path / 'out' / 'report.json').read_text())['parameters']
    assert parameters['conditional_update'] is False and parameters['ghost_test'] is False


def test_booleans_in_a_parameter_file_must_be_booleans(tmp_path, capsys):
    params = tmp_path / 'p.yaml'
    params.write_text('/detector:\n  ros__parameters:\n    ghost_test: false\n')
    assert cli.resolve_parameters(parse('separate', '--config', str(params)))[0][
        'ghost_test'] is False
    params.write_text('/detector:\n  ros__parameters:\n    ghost_test: maybe\n')
    assert run('separate', tmp_path, '--out', tmp_path / 'o', '--config', params) == 2
    err = capsys.readouterr().err
    assert err == 'dgmod: error: ghost_test must be true or false, got ' + repr('maybe') + '\n'


@pytest.mark.parametrize('command', ['separate', 'evaluate'])
def test_one_option_per_parameter_and_none_twice(command):
    parser = cli.build_parser()
    sub = parser._subparsers._group_actions[0].choices[command]
    options = [o for action in sub._actions for o in action.option_strings]
    assert len(options) == len(set(options))
    dests = {action.dest for action in sub._actions if action.help != '==SUPPRESS=='}
    offered = {spec.name for spec in cli.offline_parameters(command)}
    assert offered <= dests
    assert not {spec.name for spec in config.PARAMETERS if spec.where == 'node'} & dests
    assert ('method' in dests) == (command == 'separate')     # evaluate has --methods


def test_the_removed_threshold_option_names_its_successor(capsys):
    with pytest.raises(SystemExit) as stop:
        parse('separate', '--threshold', '0.2')
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count('\n') == 1 and 'use --mask-threshold' in err


def test_help_groups_the_advanced_parameters_apart(capsys):
    with pytest.raises(SystemExit):
        parse('separate', '--help')
    text = capsys.readouterr().out
    basic, advanced = text.split(config.ADVANCED_TITLE.split(' (')[0])
    for spec in cli.offline_parameters('separate'):
        assert cli.option_name(spec.name) + ' ' in (advanced if spec.advanced else basic)
    assert '--max-iter' in advanced and '[batch]' in advanced.split('--max-iter')[1][:300]
    assert 'Acts only with decision=global' in ' '.join(basic.split())


def test_a_parameter_that_does_nothing_is_one_warning(tmp_path, scene, capsys):
    folder = write_folder(tmp_path / 'seq', scene.frames[:8])
    assert run('separate', folder, '--out', tmp_path / 'a', '--window', 5, '--stride', 5,
               '--mask-k', 4, '--max-iter', 20) == 0
    err = [line for line in capsys.readouterr().err.splitlines() if 'warning' in line]
    assert err == ['dgmod: warning: --max-iter has no effect: it is read only by dgmod '
                   '--mode batch',                  # one line each, in the table's order
                   'dgmod: warning: --mask-k has no effect: it acts only with decision=global '
                   'and mask_threshold=0.0 (decision is adaptive, mask_threshold is 0.0)']
    assert run('separate', folder, '--out', tmp_path / 'b', '--window', 5, '--stride', 5,
               '--mask-k', 4, '--decision', 'global') == 0
    assert 'warning' not in capsys.readouterr().err


def test_evaluate_warns_of_a_parameter_no_method_reads(capsys):
    values, given = cli.resolve_parameters(parse('evaluate', '--lambda2', '0.3'))
    cli.warn_inert(values, given, 'stream', ['dgmod', 'median'])
    assert capsys.readouterr().err == ''
    cli.warn_inert(values, given, 'stream', ['median', 'mog2'])
    assert capsys.readouterr().err == ('dgmod: warning: --lambda2 has no effect: it acts only '
                                       'with method=dgmod (method is median)\n')


@pytest.mark.skipif(not sys.platform.startswith('linux'), reason='per-thread nice values: Linux')
def test_file_threads_yield_to_the_separation(tmp_path, monkeypatch):
    # The reader and the writer run at a lower priority than the thread that
    # separates, which keeps its own (core/runtime.yield_to_compute).
    def priority():
        return os.getpriority(os.PRIO_PROCESS, threading.get_native_id())
    main = priority()
    lowered = min(main + IO_THREAD_NICENESS, 19)
    produced, written = [], []

    def frames():
        for index in range(3):
            produced.append(priority())
            yield index
    assert list(cli.read_ahead(frames())) == [0, 1, 2]
    monkeypatch.setattr(cli, '_write_png', lambda path, image: written.append(priority()))
    writer = cli.PngWriter()
    writer.write(tmp_path / 'mask.png', np.zeros((2, 2), dtype=np.uint8))
    writer.close()
    assert produced == [lowered] * 3 and written == [lowered]
    assert priority() == main
