# Sourced, after `cd` to the repository, by the scripts that drive route
# 1->2 along lines through its corridor. `route_line FROM TO HEADING`
# prints the route file with the start moved FROM metres off the corridor's
# axis and turned HEADING degrees, and the goal moved TO metres off it.
route_line() {
    sed -E -e "s/start: \(x: 1.0, y: 0.0\)/start: (x: 1.0, y: $1, heading_deg: $3)/" \
        -e "s/goal: \(x: 41.7, y: 0.0,/goal: (x: 41.7, y: $2,/" \
        lab/scenarios/thesis/route-1-2.ron
}
