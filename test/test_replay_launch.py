"""replay.launch's own usage examples, loaded as roslaunch would (no master, no process)."""
import os
import re
import shlex

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
REPLAY = os.path.join(ROOT, 'launch', 'replay.launch')


def header_examples():
    """The replay.launch commands in the file's header comment, each as its arg list (an
    example goes on over the indented arg:=value lines after it)."""
    text = open(REPLAY).read()
    header = text[text.index('<!--') + 4:text.index('-->')]
    examples = []
    for line in header.splitlines():
        if re.search(r'\breplay\.launch \w+:=', line):
            words = shlex.split(line)
            examples.append(words[words.index('replay.launch') + 1:])
        elif examples and line.split() and all(re.match(r'\w+:=', w) for w in line.split()):
            examples[-1] += shlex.split(line)
    return examples


def played_args(argv):
    import roslaunch.config
    import roslaunch.xmlloader
    config = roslaunch.config.ROSLaunchConfig()
    roslaunch.xmlloader.XmlLoader(resolve_anon=False).load(REPLAY, config, verbose=False,
                                                            argv=['roslaunch'] + argv)
    (node,) = [n for n in config.nodes if n.package == 'rosbag']
    return node.args.split()


def test_every_example_plays_only_the_topics_it_names():
    # rosbag play --wait-for-subscribers without --topics waits for a subscriber on every
    # topic of the bag: the header's first example (a recorded session into
    # ur10_dual.launch sender:=false) never played, the bag's Hand and gesture topics unread.
    examples = header_examples()
    assert len(examples) == 2, examples
    for argv in examples:
        args = played_args(argv)
        assert '--wait-for-subscribers' in args
        assert '--topics' in args, argv
        topics = dict(a.split(':=', 1) for a in argv)['topics'].split()
        assert args[args.index('--topics') + 1:] == topics, (argv, args)

