"""Reading a YAML file a user hands in (a gesture script, gesture bindings, a cell
config): each way it can be bad is one line naming the file, not a traceback."""
import yaml


class YamlFileError(ValueError):
    """A YAML file that cannot be read or parsed: one line naming it (and the line of the
    file where the parser stopped, when it knows)."""


def load_yaml_file(path, what):
    """The data in the YAML file at `path`; `what` names the file's kind in errors
    ('gesture script'). Raises YamlFileError."""
    try:
        with open(path, encoding='utf-8') as f:
            return yaml.safe_load(f)
    except OSError as e:
        why = 'cannot read (%s)' % (e.strerror or e)
    except UnicodeDecodeError as e:
        why = 'not UTF-8 text (%s)' % e
    except yaml.YAMLError as e:     # its text spans lines and points into the file
        mark = getattr(e, 'problem_mark', None)
        why = 'not valid YAML (%s%s)' % ('line %d: ' % (mark.line + 1) if mark else '',
                                         getattr(e, 'problem', None) or ' '.join(str(e).split()))
    except RecursionError:          # the YAML composer recurses per nesting level
        why = 'nested too deeply'
    raise YamlFileError('%s %s: %s' % (what, path, why))
