/* LD_PRELOAD shim (built by tools/setup.sh, enabled by env.sh): while ROS_HOSTNAME (or,
 * if unset, ROS_IP) names a loopback address, a bind() to the wildcard address (0.0.0.0
 * or ::) binds to loopback instead. rospy and rosmaster already bind to ROS_IP, but
 * roscpp nodes (rosout, robot_state_publisher, rviz) listen on 0.0.0.0 whatever ROS_IP
 * says; with this they are unreachable from other hosts, as the environment promises.
 * Any other ROS_IP / ROS_HOSTNAME (a multi-host set-up) turns the shim off. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <netinet/in.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>

static int loopback_only(void)
{
    const char *host = getenv("ROS_HOSTNAME");
    const char *name = (host && *host) ? host : getenv("ROS_IP");
    if (!name || !*name)
        return 0;
    return strncmp(name, "127.", 4) == 0 || strcmp(name, "localhost") == 0
        || strcmp(name, "::1") == 0;
}

int bind(int fd, const struct sockaddr *addr, socklen_t len)
{
    static int (*real_bind)(int, const struct sockaddr *, socklen_t);
    static int active = -1;
    if (!real_bind)
        real_bind = (int (*)(int, const struct sockaddr *, socklen_t))dlsym(RTLD_NEXT, "bind");
    if (active < 0)
        active = loopback_only();
    if (active && addr && addr->sa_family == AF_INET && len >= sizeof(struct sockaddr_in)) {
        struct sockaddr_in a;
        memcpy(&a, addr, sizeof a);
        if (a.sin_addr.s_addr == htonl(INADDR_ANY)) {
            a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
            return real_bind(fd, (const struct sockaddr *)&a, sizeof a);
        }
    } else if (active && addr && addr->sa_family == AF_INET6
               && len >= sizeof(struct sockaddr_in6)) {
        struct sockaddr_in6 a;
        memcpy(&a, addr, sizeof a);
        if (IN6_IS_ADDR_UNSPECIFIED(&a.sin6_addr)) {
            a.sin6_addr = in6addr_loopback;
            return real_bind(fd, (const struct sockaddr *)&a, sizeof a);
        }
    }
    return real_bind(fd, addr, len);
}
