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
    if os.path.isdir(out):
        return 'a folder: name a file'
    folder = os.path.dirname(os.path.abspath(out))
    if not os.path.isdir(folder):
        return 'no folder %s' % folder
    if os.path.exists(out):
        if not (os.path.isfile(out) or stat.S_ISCHR(os.stat(out).st_mode)):
            return 'no regular file'      # a pipe would block the check below
        for path in inputs:
            if path not in (None, '', '-') and os.path.exists(path) \
                    and os.path.samefile(out, path):
                return 'it is the input %s: it would be overwritten' % path
        mode = 'ab'       # opened to append, an existing file is left as it is
    else:
        mode = 'xb'
    # Tried, not judged by os.access: root passes that test where no file can be made.
    try:
        with open(out, mode):
            pass
        if mode == 'xb':
            os.remove(out)
    except OSError as e:
        return 'cannot write it (%s)' % (e.strerror or e)
    return None
