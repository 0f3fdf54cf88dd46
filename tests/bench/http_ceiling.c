/* http_ceiling.c — the reference bench_http.py measures isomeshd against: libmicrohttpd alone,
 * configured as isomeshd configures it (its polling threads, server/common/http_loops.h: two
 * per core, each a daemon in external epoll mode on the shared socket; 256 KB of unsent bytes
 * per socket, suspend/resume allowed, answer on the handler's second call), answering every
 * GET with one file's bytes from memory. Whatever
 * isomeshd adds (routing, cache lookup, headers, log line, metrics) shows up as the
 * difference.
 *
 *   http_ceiling PORT FILE     serves until SIGTERM/SIGINT */
#include <arpa/inet.h>
#include <microhttpd.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "server/common/http_loops.h"

#define CONNECTION_LIMIT 4000u   /* as isomeshd's http.c */
#define THREADS_PER_CORE 2u       /* as isomeshd's http.c */
#define NOTSENT_LOWAT (256 << 10) /* as isomeshd's http.c */

/* A listening socket on 127.0.0.1:port with isomeshd's socket options; -1 on failure. */
static int listen_on(int port)
{
    int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    int one = 1, lowat = NOTSENT_LOWAT;
    struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((unsigned short)port)};
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (fd < 0 || setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0 ||
        setsockopt(fd, IPPROTO_TCP, TCP_NOTSENT_LOWAT, &lowat, sizeof lowat) != 0 ||
        bind(fd, (struct sockaddr *)&sa, sizeof sa) != 0 || listen(fd, 1024) != 0) {
        if (fd >= 0)
            close(fd);
        return -1;
    }
    return fd;
}

static unsigned char *body;
static size_t body_len;

static enum MHD_Result answer(void *cls, struct MHD_Connection *c, const char *url,
                              const char *method, const char *version, const char *upload,
                              size_t *upload_size, void **con_cls)
{
    (void)cls, (void)url, (void)method, (void)version, (void)upload, (void)upload_size;
    if (!*con_cls) {
        *con_cls = c;
        return MHD_YES;
    }
    struct MHD_Response *r =
        MHD_create_response_from_buffer(body_len, body, MHD_RESPMEM_PERSISTENT);
    MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE, "application/octet-stream");
    enum MHD_Result ok = MHD_queue_response(c, MHD_HTTP_OK, r);
    MHD_destroy_response(r);
    return ok;
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: http_ceiling PORT FILE\n");
        return 2;
    }
    FILE *f = fopen(argv[2], "rb");
    if (!f || fseek(f, 0, SEEK_END) != 0) {
        perror(argv[2]);
        return 1;
    }
    long n = ftell(f);
    rewind(f);
    body = malloc(n > 0 ? (size_t)n : 1);
    body_len = body ? fread(body, 1, (size_t)n, f) : 0;
    fclose(f);
    if (!body || body_len != (size_t)n)
        return 1;
    sigset_t stop;
    sigemptyset(&stop);
    sigaddset(&stop, SIGTERM);
    sigaddset(&stop, SIGINT);
    pthread_sigmask(SIG_BLOCK, &stop, NULL);
    signal(SIGPIPE, SIG_IGN);
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    unsigned threads = THREADS_PER_CORE * (cores > 0 ? (unsigned)cores : 1u);
    int lfd = listen_on(atoi(argv[1]));
    struct MHD_OptionItem opts[] = {{MHD_OPTION_SIGPIPE_HANDLED_BY_APP, 1, NULL},
                                    {MHD_OPTION_END, 0, NULL}};
    ism_http_loops *d = lfd < 0 ? NULL : ism_http_loops_new(threads);
    if (!d || !ism_http_loops_start(d, MHD_ALLOW_SUSPEND_RESUME, lfd, CONNECTION_LIMIT, answer,
                                    NULL, opts, NULL)) {
        ism_http_loops_stop(d);
        fprintf(stderr, "http_ceiling: cannot listen on port %s\n", argv[1]);
        return 1;
    }
    int sig;
    sigwait(&stop, &sig);
    ism_http_loops_stop(d);
    close(lfd);
    free(body);
    return 0;
}
