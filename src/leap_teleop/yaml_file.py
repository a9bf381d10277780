"""Reading a YAML file a user hands in (a gesture script, gesture bindings, a cell
config): each way it can be bad is one line naming the file, not a traceback. A key given
twice in one mapping is refused: PyYAML keeps the last one, and the earlier one (a safety
binding written first) would be dropped without a word."""
import yaml


class YamlFileError(ValueError):
    """A YAML file that cannot be read or parsed: one line naming it (and the line of the
    file where the parser stopped, when it knows)."""


class _DuplicateKey(yaml.YAMLError):
    def __init__(self, key, first, again):
        super().__init__('%r given twice (lines %d and %d)' % (key, first.line + 1, again.line + 1))


class _UniqueKeyLoader(yaml.SafeLoader):
    """safe_load's loader, refusing a key given twice in one mapping (a merge key `<<`
    may still be overridden: that is what it is for)."""

    def flatten_mapping(self, node):
        # Each mapping's own keys, once, before flattening writes the merged ones into it
        # (a merge source is flattened when first used, which may be before its own turn).
        checked = self.__dict__.setdefault('_checked', set())
        if id(node) not in checked:
            checked.add(id(node))
            seen = {}
            for key_node, _ in node.value:
                if key_node.tag == 'tag:yaml.org,2002:merge':
                    continue
                key = self.construct_object(key_node, deep=True)
                try:
                    first = seen.setdefault(key, key_node.start_mark)
                except TypeError:       # an unhashable key: the constructor says so
                    continue
                if first is not key_node.start_mark:
                    raise _DuplicateKey(key, first, key_node.start_mark)
        super().flatten_mapping(node)


def load_yaml_file(path, what):
    """The data in the YAML file at `path`; `what` names the file's kind in errors
    ('gesture script'). Raises YamlFileError."""
    try:
        with open(path, encoding='utf-8') as f:
            return yaml.load(f, Loader=_UniqueKeyLoader)
    except OSError as e:
        why = 'cannot read (%s)' % (e.strerror or e)
    except UnicodeDecodeError as e:
        why = 'not UTF-8 text (%s)' % e
    except _DuplicateKey as e:
        why = str(e)
    except yaml.YAMLError as e:     # its text spans lines and points into the file
        mark = getattr(e, 'problem_mark', None)
        why = 'not valid YAML (%s%s)' % ('line %d: ' % (mark.line + 1) if mark else '',
                                         getattr(e, 'problem', None) or ' '.join(str(e).split()))
    except RecursionError:          # the YAML composer recurses per nesting level
        why = 'nested too deeply'
    raise YamlFileError('%s %s: %s' % (what, path, why))
