"""Message and service classes named as ardrone_autonomy's (ardrone_autonomy/...), built
at run time from the field lists, with MD5 sums computed here by genmsg: what a client
compiled against the real driver sends on the wire. Nothing from leap_teleop's generated
classes is reused, so a type whose definition drifted fails the handshake."""
import os

import genmsg
import genmsg.gentools
import genmsg.msg_loader
import genpy.dynamic
import rospkg

PKG = 'ardrone_autonomy'
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def _text(kind, name):
    with open(os.path.join(ROOT, kind, '%s.%s' % (name, kind))) as f:
        return f.read()


def _header_text():
    path = os.path.join(rospkg.RosPack().get_path('std_msgs'), 'msg', 'Header.msg')
    with open(path) as f:
        return f.read()


def message(name, deps=()):
    """The ardrone_autonomy/<name> message class (deps: nested driver message names)."""
    sep = '\n' + '=' * 80 + '\n'
    text = _text('msg', name)
    if 'Header header' in text:
        text += sep + 'MSG: std_msgs/Header\n' + _header_text()
    for dep in deps:
        text += sep + 'MSG: %s/%s\n' % (PKG, dep) + _text('msg', dep)
    return genpy.dynamic.generate_dynamic('%s/%s' % (PKG, name), text)['%s/%s' % (PKG, name)]


def service(name):
    """The ardrone_autonomy/<name> service class, its MD5 computed by genmsg."""
    text = _text('srv', name)
    ctx = genmsg.MsgContext.create_default()
    spec = genmsg.msg_loader.load_srv_from_string(ctx, text, '%s/%s' % (PKG, name))
    md5 = genmsg.gentools.compute_md5(ctx, spec)
    req_text, resp_text = text.split('\n---\n')
    req = genpy.dynamic.generate_dynamic('%s/%sRequest' % (PKG, name),
                                         req_text)['%s/%sRequest' % (PKG, name)]
    resp = genpy.dynamic.generate_dynamic('%s/%sResponse' % (PKG, name),
                                          resp_text)['%s/%sResponse' % (PKG, name)]
    req._md5sum = genmsg.gentools.compute_md5(ctx, spec.request)
    resp._md5sum = genmsg.gentools.compute_md5(ctx, spec.response)
    return type(name, (object,), {'_type': '%s/%s' % (PKG, name), '_md5sum': md5,
                                  '_request_class': req, '_response_class': resp})
