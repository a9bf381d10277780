"""The check a tool makes on its output file before its work starts, so that a take
recorded or a model fitted is not lost at the end and no input is overwritten."""
import os
import stat


def output_problem(out, inputs=()):
    """Why `out` cannot be written, in a phrase, or None: no name, a folder, no such
    folder, a place that takes no such file (read-only, a name too long, ...), or one of
    `inputs` (paths; None, '' and '-' are skipped) that writing would overwrite."""
    if not out or not out.strip():
        return 'name a file'
    if os.path.islink(out) and not os.path.exists(out):
        target = os.path.realpath(out)      # a link to a file still to be made: the write makes it
        if not os.path.islink(target):
            out = target
    if os.path.isdir(out):
        return 'a folder: name a file'
    folder = os.path.dirname(os.path.abspath(out))
    if not os.path.isdir(folder):
        return 'no folder %s' % folder
    if os.path.exists(out):
        mode = os.stat(out).st_mode
        if stat.S_ISFIFO(mode):
            return _pipe_problem(out)
        if not (stat.S_ISREG(mode) or stat.S_ISCHR(mode)):
            return 'no regular file'
        for path in inputs:
            if path not in (None, '', '-') and os.path.exists(path) \
                    and os.path.samefile(out, path):
                return 'it is the input %s: it would be overwritten' % path
        how = 'ab'        # opened to append, an existing file is left as it is
    else:
        how = 'xb'
    # Tried, not judged by os.access: root passes that test where no file can be made.
    try:
        with open(out, how):
            pass
        if how == 'xb':
            os.remove(out)
    except OSError as e:
        return 'cannot write it (%s)' % (e.strerror or e)
    return None


def _pipe_problem(out):
    """A named pipe takes output while something reads it; a plain open would wait."""
    try:
        os.close(os.open(out, os.O_WRONLY | os.O_NONBLOCK))
    except OSError:
        return 'a pipe that nothing reads'
    return None
