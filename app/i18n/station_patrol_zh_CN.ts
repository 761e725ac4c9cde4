<?xml version="1.0" encoding="utf-8"?>
<!DOCTYPE TS>
<TS version="2.1" language="zh_CN">
<context>
    <name>Alarm</name>
    <message>
        <source>{name} {value}{unit} above limit {limit}{unit}</source>
        <translation>{name} {value}{unit}，高于限值 {limit}{unit}</translation>
    </message>
    <message>
        <source>{name} {value}{unit} below limit {limit}{unit}</source>
        <translation>{name} {value}{unit}，低于限值 {limit}{unit}</translation>
    </message>
    <message>
        <source>{name} rising {value}{unit}/min (limit {limit}{unit}/min)</source>
        <translation>{name} 上升速率 {value}{unit}/min（限值 {limit}{unit}/min）</translation>
    </message>
    <message>
        <source>{name}: no data for more than {limit} s</source>
        <translation>{name}：超过 {limit} s 无数据</translation>
    </message>
    <message>
        <source>{text}: cleared</source>
        <translation>{text}：已消除</translation>
    </message>
    <message>
        <source>{name} back to {value}{unit} (limit {limit}{unit})</source>
        <translation>{name} 恢复至 {value}{unit}（限值 {limit}{unit}）</translation>
    </message>
    <message>
        <source>Alarm flood: more than {max} alarms in {window} s — the list is grouped by source</source>
        <translation>报警泛滥：{window} s 内超过 {max} 条报警 — 列表按来源分组</translation>
    </message>
</context>
<context>
    <name>AlarmBanner</name>
    <message>
        <source>No unacknowledged alarms ({standing} standing, acknowledged)</source>
        <translation>无未确认报警（{standing} 条持续中，已确认）</translation>
    </message>
    <message>
        <source>No active alarms</source>
        <translation>无报警</translation>
    </message>
    <message>
        <source>  (returned to normal)</source>
        <translation>  （已恢复正常）</translation>
    </message>
    <message>
        <source>   (+{n} more unacknowledged)</source>
        <translation>   （另有 {n} 条未确认）</translation>
    </message>
    <message>
        <source>ALARM FLOOD — </source>
        <translation>报警泛滥 — </translation>
    </message>
    <message>
        <source>E-STOP ENGAGED — the robot holds still until reset (Ctrl+Shift+R)</source>
        <translation>急停已触发 — 机器人保持静止，直至复位（Ctrl+Shift+R）</translation>
    </message>
    <message>
        <source>FAIL-SAFE STOP — the robot stopped itself</source>
        <translation>失效安全停车 — 机器人已自行停车</translation>
    </message>
    <message>
        <source>The most severe unacknowledged alarm (Ctrl+K acknowledges the selected alarm, Ctrl+Shift+K all visible ones)</source>
        <translation>最严重的未确认报警（Ctrl+K 确认所选报警，Ctrl+Shift+K 确认全部可见报警）</translation>
    </message>
</context>
<context>
    <name>AlarmPanel</name>
    <message>
        <source>Time</source>
        <translation>时间</translation>
    </message>
    <message>
        <source>Priority</source>
        <translation>优先级</translation>
    </message>
    <message>
        <source>Source</source>
        <translation>来源</translation>
    </message>
    <message>
        <source>Alarm</source>
        <translation>报警</translation>
    </message>
    <message>
        <source>Value</source>
        <translation>数值</translation>
    </message>
    <message>
        <source>Limit</source>
        <translation>限值</translation>
    </message>
    <message>
        <source>State</source>
        <translation>状态</translation>
    </message>
    <message>
        <source>Comment</source>
        <translation>备注</translation>
    </message>
    <message>
        <source>ACTIVE, unacknowledged</source>
        <translation>报警中，未确认</translation>
    </message>
    <message>
        <source>ACTIVE, acknowledged</source>
        <translation>报警中，已确认</translation>
    </message>
    <message>
        <source>CLEARED, unacknowledged</source>
        <translation>已消除，未确认</translation>
    </message>
    <message>
        <source>SHELVED</source>
        <translation>已搁置</translation>
    </message>
    <message>
        <source>OUT OF SERVICE</source>
        <translation>已停用</translation>
    </message>
    <message>
        <source>normal</source>
        <translation>正常</translation>
    </message>
    <message>
        <source>All listed</source>
        <translation>全部</translation>
    </message>
    <message>
        <source>Unacknowledged</source>
        <translation>未确认</translation>
    </message>
    <message>
        <source>Active</source>
        <translation>报警中</translation>
    </message>
    <message>
        <source>Cleared, unacknowledged</source>
        <translation>已消除，未确认</translation>
    </message>
    <message>
        <source>Shelved</source>
        <translation>已搁置</translation>
    </message>
    <message>
        <source>Out of service</source>
        <translation>已停用</translation>
    </message>
    <message>
        <source>set</source>
        <translation>触发</translation>
    </message>
    <message>
        <source>clear</source>
        <translation>已解除</translation>
    </message>
    <message>
        <source> until {time}</source>
        <translation> 至 {time}</translation>
    </message>
    <message>
        <source>{n} alarms ({unacked} unacknowledged)</source>
        <translation>{n} 条报警（{unacked} 条未确认）</translation>
    </message>
    <message>
        <source>{label} high</source>
        <translation>{label} 高</translation>
    </message>
    <message>
        <source>{label} low</source>
        <translation>{label} 低</translation>
    </message>
    <message>
        <source>All priorities</source>
        <translation>全部优先级</translation>
    </message>
    <message>
        <source>All sources</source>
        <translation>全部来源</translation>
    </message>
    <message>
        <source>no active alarms</source>
        <translation>无报警</translation>
    </message>
    <message>
        <source>Mute</source>
        <translation>静音</translation>
    </message>
    <message>
        <source>Silence the alarm sounds (Ctrl+M)</source>
        <translation>关闭报警声音（Ctrl+M）</translation>
    </message>
    <message>
        <source>Group by source</source>
        <translation>按来源分组</translation>
    </message>
    <message>
        <source>Acknowledge (Ctrl+K)</source>
        <translation>确认（Ctrl+K）</translation>
    </message>
    <message>
        <source>Acknowledge visible (Ctrl+Shift+K)</source>
        <translation>确认可见报警（Ctrl+Shift+K）</translation>
    </message>
    <message>
        <source>Shelve…</source>
        <translation>搁置…</translation>
    </message>
    <message>
        <source>Unshelve</source>
        <translation>取消搁置</translation>
    </message>
    <message>
        <source>Out of service…</source>
        <translation>停用…</translation>
    </message>
    <message>
        <source>Back in service</source>
        <translation>恢复投用</translation>
    </message>
    <message>
        <source>Reset latch</source>
        <translation>复位闭锁</translation>
    </message>
    <message>
        <source>Release a latched alarm (gas A2, over-range) once the value is back below its set-point less its deadband; a reset is not an acknowledgement</source>
        <translation>数值回落到设定值减死区以下后，解除闭锁报警（燃气 A2、超量程）；复位不等于确认</translation>
    </message>
    <message>
        <source>Acknowledge selected alarm</source>
        <translation>确认所选报警</translation>
    </message>
    <message>
        <source>Acknowledge all visible alarms</source>
        <translation>确认全部可见报警</translation>
    </message>
    <message>
        <source>Mute alarm sounds</source>
        <translation>报警静音</translation>
    </message>
    <message>
        <source>event log</source>
        <translation>事件日志</translation>
    </message>
    <message>
        <source>Event log</source>
        <translation>事件日志</translation>
    </message>
    <message>
        <source> (latch reset by {0})</source>
        <translation>（闭锁由 {0} 复位）</translation>
    </message>
    <message>
        <source> by {user}</source>
        <translation>（{user}）</translation>
    </message>
    <message>
        <source>{label}: comment by {user}: {text}</source>
        <translation>{label}：{user} 备注：{text}</translation>
    </message>
    <message>
        <source>ALARM FLOOD: {n} alarms in the last {window} s (more than {max}). The list is grouped by source; every alarm is still recorded.</source>
        <translation>报警泛滥：最近 {window} s 内 {n} 条报警（超过 {max} 条）。列表按来源分组；每条报警仍全部记录。</translation>
    </message>
    <message>
        <source>{active} active, {unack} unacknowledged, {listed} listed</source>
        <translation>{active} 条报警中，{unack} 条未确认，共列出 {listed} 条</translation>
    </message>
    <message>
        <source>cannot shelve {key}: {why}</source>
        <translation>无法搁置 {key}：{why}</translation>
    </message>
    <message>
        <source>cannot take {key} out of service: {why}</source>
        <translation>无法停用 {key}：{why}</translation>
    </message>
    <message>
        <source>cannot reset {key}: {why}</source>
        <translation>无法复位 {key}：{why}</translation>
    </message>
</context>
<context>
    <name>AlarmSettingsDialog</name>
    <message>
        <source>Limits</source>
        <translation>限值</translation>
    </message>
    <message>
        <source>Label</source>
        <translation>名称</translation>
    </message>
    <message>
        <source>Unit</source>
        <translation>单位</translation>
    </message>
    <message>
        <source>Low</source>
        <translation>下限</translation>
    </message>
    <message>
        <source>High</source>
        <translation>上限</translation>
    </message>
    <message>
        <source>Deadband</source>
        <translation>死区</translation>
    </message>
    <message>
        <source>Priority</source>
        <translation>优先级</translation>
    </message>
    <message>
        <source>On delay s</source>
        <translation>触发延时 s</translation>
    </message>
    <message>
        <source>Off delay s</source>
        <translation>解除延时 s</translation>
    </message>
    <message>
        <source>Rate of rise</source>
        <translation>上升速率</translation>
    </message>
    <message>
        <source>Rise per min</source>
        <translation>每分钟上升</translation>
    </message>
    <message>
        <source>Window s</source>
        <translation>窗口 s</translation>
    </message>
    <message>
        <source>Stale data</source>
        <translation>数据过期</translation>
    </message>
    <message>
        <source>After s</source>
        <translation>超过 s</translation>
    </message>
    <message>
        <source>Robot faults</source>
        <translation>机器人故障</translation>
    </message>
    <message>
        <source>Text</source>
        <translation>文字</translation>
    </message>
    <message>
        <source>Alarm settings</source>
        <translation>报警设置</translation>
    </message>
    <message>
        <source>Flag</source>
        <translation>标志位</translation>
    </message>
    <message>
        <source>Channel</source>
        <translation>通道</translation>
    </message>
    <message>
        <source> alarms in {s} s</source>
        <translation> 条报警 / {s} s</translation>
    </message>
    <message>
        <source>Save as TOML…</source>
        <translation>另存为 TOML…</translation>
    </message>
    <message>
        <source>Limits: an empty Low or High means no such limit. Delays in seconds, deadbands in the channel&apos;s unit.</source>
        <translation>限值：下限或上限留空表示不设该限值。延时单位为秒，死区单位与通道单位相同。</translation>
    </message>
    <message>
        <source>Flood guard above</source>
        <translation>报警泛滥阈值</translation>
    </message>
    <message>
        <source>Save alarm rules</source>
        <translation>保存报警规则</translation>
    </message>
    <message>
        <source>TOML (*.toml)</source>
        <translation>TOML (*.toml)</translation>
    </message>
    <message>
        <source>could not save {path}: {why}</source>
        <translation>无法保存 {path}：{why}</translation>
    </message>
</context>
<context>
    <name>AlarmText</name>
    <message>
        <source>Gas</source>
        <translation>燃气浓度</translation>
    </message>
    <message>
        <source>Temperature</source>
        <translation>温度</translation>
    </message>
    <message>
        <source>Humidity</source>
        <translation>湿度</translation>
    </message>
    <message>
        <source>Battery</source>
        <translation>电池电压</translation>
    </message>
    <message>
        <source>Gas A2</source>
        <translation>燃气 A2</translation>
    </message>
    <message>
        <source>Gas over-range</source>
        <translation>燃气超量程</translation>
    </message>
    <message>
        <source>Gas high (robot)</source>
        <translation>燃气浓度高（机器人）</translation>
    </message>
    <message>
        <source>Temperature high (robot)</source>
        <translation>温度高（机器人）</translation>
    </message>
    <message>
        <source>Humidity high (robot)</source>
        <translation>湿度高（机器人）</translation>
    </message>
    <message>
        <source>Obstacle near</source>
        <translation>障碍物过近</translation>
    </message>
    <message>
        <source>Battery low (robot)</source>
        <translation>电量低（机器人）</translation>
    </message>
    <message>
        <source>Fail-safe stop</source>
        <translation>失效安全停车</translation>
    </message>
    <message>
        <source>Emergency stop active</source>
        <translation>急停已触发</translation>
    </message>
    <message>
        <source>Sensor fault</source>
        <translation>传感器故障</translation>
    </message>
    <message>
        <source>Link to the robot lost</source>
        <translation>与机器人的链路中断</translation>
    </message>
    <message>
        <source>Archive writes failing (data held in memory)</source>
        <translation>档案写入失败（数据暂存内存）</translation>
    </message>
    <message>
        <source>Gas sensor fault</source>
        <translation>燃气传感器故障</translation>
    </message>
    <message>
        <source>Gas rate of rise</source>
        <translation>燃气浓度上升速率</translation>
    </message>
    <message>
        <source>Gas stale</source>
        <translation>燃气数据过期</translation>
    </message>
    <message>
        <source>Temperature stale</source>
        <translation>温度数据过期</translation>
    </message>
    <message>
        <source>Humidity stale</source>
        <translation>湿度数据过期</translation>
    </message>
    <message>
        <source>Battery stale</source>
        <translation>电池数据过期</translation>
    </message>
</context>
<context>
    <name>CalibrationDialog</name>
    <message>
        <source>centre</source>
        <translation>轴心</translation>
    </message>
    <message>
        <source>minimum tick</source>
        <translation>最小刻度</translation>
    </message>
    <message>
        <source>maximum tick</source>
        <translation>最大刻度</translation>
    </message>
    <message>
        <source>Calibrate a gauge profile</source>
        <translation>标定仪表参数</translation>
    </message>
    <message>
        <source>new gauge profile</source>
        <translation>新建仪表参数</translation>
    </message>
    <message>
        <source>inspection point {name} ({gauge})</source>
        <translation>巡检点 {name}（{gauge}）</translation>
    </message>
    <message>
        <source>Suggest points</source>
        <translation>建议标定点</translation>
    </message>
    <message>
        <source>Place the three points where the reader finds them</source>
        <translation>将三个点放在识别程序找到的位置</translation>
    </message>
    <message>
        <source>no frame</source>
        <translation>无画面</translation>
    </message>
    <message>
        <source>Undo point</source>
        <translation>撤销点</translation>
    </message>
    <message>
        <source>MPa</source>
        <translation>MPa</translation>
    </message>
    <message>
        <source>scale runs clockwise</source>
        <translation>刻度顺时针增大</translation>
    </message>
    <message>
        <source>normal band</source>
        <translation>正常范围</translation>
    </message>
    <message>
        <source>Store for</source>
        <translation>保存到</translation>
    </message>
    <message>
        <source>Name</source>
        <translation>名称</translation>
    </message>
    <message>
        <source>Unit</source>
        <translation>单位</translation>
    </message>
    <message>
        <source>Value at minimum tick</source>
        <translation>最小刻度值</translation>
    </message>
    <message>
        <source>Value at maximum tick</source>
        <translation>最大刻度值</translation>
    </message>
    <message>
        <source>…</source>
        <translation>…</translation>
    </message>
    <message>
        <source>Alarm</source>
        <translation>报警</translation>
    </message>
    <message>
        <source>Save to</source>
        <translation>保存至</translation>
    </message>
    <message>
        <source>with the route {name}</source>
        <translation>随路线 {name} 保存</translation>
    </message>
    <message>
        <source>choose an inspection point, or name a known gauge type, to get a suggestion</source>
        <translation>请选择巡检点，或填写已知的仪表型号，以获得建议</translation>
    </message>
    <message>
        <source>Looking for the pivot and the scale&apos;s ends …</source>
        <translation>正在查找指针轴心和刻度两端…</translation>
    </message>
    <message>
        <source>the reader found no dial here; click the points</source>
        <translation>未在此处识别到表盘；请手动点选各点</translation>
    </message>
    <message>
        <source>Click the {step}.</source>
        <translation>请点击{step}。</translation>
    </message>
    <message>
        <source>All three points set; fill in and save.</source>
        <translation>三个点均已设置；请填写后保存。</translation>
    </message>
    <message>
        <source>no profile for this gauge</source>
        <translation>此仪表无参数</translation>
    </message>
</context>
<context>
    <name>Channel</name>
    <message>
        <source>Gas</source>
        <translation>燃气浓度</translation>
    </message>
    <message>
        <source>Temperature</source>
        <translation>温度</translation>
    </message>
    <message>
        <source>Humidity</source>
        <translation>湿度</translation>
    </message>
    <message>
        <source>Battery</source>
        <translation>电池电压</translation>
    </message>
    <message>
        <source>Obstacle left</source>
        <translation>左侧障碍物</translation>
    </message>
    <message>
        <source>Obstacle front</source>
        <translation>前方障碍物</translation>
    </message>
    <message>
        <source>Obstacle right</source>
        <translation>右侧障碍物</translation>
    </message>
    <message>
        <source>Wheel left</source>
        <translation>左轮</translation>
    </message>
    <message>
        <source>Wheel right</source>
        <translation>右轮</translation>
    </message>
    <message>
        <source>Yaw rate</source>
        <translation>横摆角速度</translation>
    </message>
    <message>
        <source>Commanded speed</source>
        <translation>指令速度</translation>
    </message>
    <message>
        <source>Commanded turn</source>
        <translation>指令转向</translation>
    </message>
</context>
<context>
    <name>Control</name>
    <message>
        <source>control is free</source>
        <translation>控制权空闲</translation>
    </message>
    <message>
        <source>you have control</source>
        <translation>本机持有控制权</translation>
    </message>
    <message>
        <source> — {who} asks for it</source>
        <translation> — {who} 请求控制权</translation>
    </message>
    <message>
        <source>view only — {holder} has control</source>
        <translation>仅查看 — {holder} 持有控制权</translation>
    </message>
</context>
<context>
    <name>ControlPanel</name>
    <message>
        <source>EMERGENCY STOP  (Esc / F1)</source>
        <translation>急停  (Esc / F1)</translation>
    </message>
    <message>
        <source>Stops the robot at once. Keys: Esc or F1</source>
        <translation>立即停止机器人。按键：Esc 或 F1</translation>
    </message>
    <message>
        <source>Reset e-stop  (Ctrl+Shift+R)</source>
        <translation>急停复位  (Ctrl+Shift+R)</translation>
    </message>
    <message>
        <source>REPLAY — view only: no drive, no e-stop, no commands (nothing here reaches a robot)</source>
        <translation>回放 — 仅查看：不能驾驶、急停或发送指令（此处操作不会到达机器人）</translation>
    </message>
    <message>
        <source>NO LINK — drive and commands are off until the robot answers again; the e-stop is still tried and says whether it arrived</source>
        <translation>无链路 — 机器人恢复应答前，驾驶和指令不可用；急停仍会尝试发送，并提示是否送达</translation>
    </message>
    <message>
        <source>▲ Forward</source>
        <translation>▲ 前进</translation>
    </message>
    <message>
        <source>▼ Back</source>
        <translation>▼ 后退</translation>
    </message>
    <message>
        <source>◀ Left</source>
        <translation>◀ 左转</translation>
    </message>
    <message>
        <source>Right ▶</source>
        <translation>右转 ▶</translation>
    </message>
    <message>
        <source>■ Stop</source>
        <translation>■ 停止</translation>
    </message>
    <message>
        <source>Stop driving (Space)</source>
        <translation>停止行驶（Space）</translation>
    </message>
    <message>
        <source>Drive speed (+ / - keys)</source>
        <translation>行驶速度（+ / - 键）</translation>
    </message>
    <message>
        <source>Speed</source>
        <translation>速度</translation>
    </message>
    <message>
        <source>mode —</source>
        <translation>模式 —</translation>
    </message>
    <message>
        <source>Battery</source>
        <translation>电量</translation>
    </message>
    <message>
        <source>— %</source>
        <translation>— %</translation>
    </message>
    <message>
        <source>Request control</source>
        <translation>申请控制权</translation>
    </message>
    <message>
        <source>Ask the desk that has control to hand it over</source>
        <translation>请求持有控制权的操作台移交控制权</translation>
    </message>
    <message>
        <source>Drive (arrows / WASD, Space stops)</source>
        <translation>驾驶（方向键 / WASD，Space 停止）</translation>
    </message>
    <message>
        <source>no link — control unknown</source>
        <translation>无链路 — 控制权未知</translation>
    </message>
    <message>
        <source>mode {name}</source>
        <translation>模式 {name}</translation>
    </message>
</context>
<context>
    <name>DataPanel</name>
    <message>
        <source>high {limit} {unit}</source>
        <translation>上限 {limit} {unit}</translation>
    </message>
    <message>
        <source>low {limit} {unit}</source>
        <translation>下限 {limit} {unit}</translation>
    </message>
    <message>
        <source>Time window of the plots (Ctrl+1 / Ctrl+2 / Ctrl+3)</source>
        <translation>曲线时间窗口（Ctrl+1 / Ctrl+2 / Ctrl+3）</translation>
    </message>
    <message>
        <source>Window:</source>
        <translation>窗口：</translation>
    </message>
    <message>
        <source>Alarm trend</source>
        <translation>报警趋势</translation>
    </message>
</context>
<context>
    <name>Desk</name>
    <message>
        <source>Archive not available, nothing is archived: {why}</source>
        <translation>档案不可用，不会存档任何数据：{why}</translation>
    </message>
</context>
<context>
    <name>Estop</name>
    <message>
        <source>E-STOP NOT DELIVERED</source>
        <translation>急停未送达</translation>
    </message>
    <message>
        <source>use the robot&apos;s own stop</source>
        <translation>请使用机器人本体急停</translation>
    </message>
    <message>
        <source>link down</source>
        <translation>链路断开</translation>
    </message>
    <message>
        <source>E-stop sent {time} — waiting for the robot&apos;s acknowledgement</source>
        <translation>急停已于 {time} 发送 — 等待机器人确认</translation>
    </message>
    <message>
        <source>refused by the robot ({why})</source>
        <translation>被机器人拒绝（{why}）</translation>
    </message>
    <message>
        <source>no reason given</source>
        <translation>未给出原因</translation>
    </message>
    <message>
        <source>E-stop sent {sent}, acknowledged by the robot at {acked}</source>
        <translation>急停已于 {sent} 发送，机器人于 {acked} 确认</translation>
    </message>
    <message>
        <source>link lost before the robot acknowledged</source>
        <translation>机器人确认前链路中断</translation>
    </message>
    <message>
        <source> (the robot now reports its e-stop engaged)</source>
        <translation>（机器人现已报告急停触发）</translation>
    </message>
    <message>
        <source>no acknowledgement from the robot within {s} s</source>
        <translation>{s} s 内未收到机器人确认</translation>
    </message>
</context>
<context>
    <name>EventLog</name>
    <message>
        <source>ALARM</source>
        <translation>报警</translation>
    </message>
    <message>
        <source>WARN</source>
        <translation>警告</translation>
    </message>
    <message>
        <source>ERROR</source>
        <translation>错误</translation>
    </message>
    <message>
        <source>info</source>
        <translation>信息</translation>
    </message>
    <message>
        <source>desk</source>
        <translation>操作台</translation>
    </message>
    <message>
        <source>robot</source>
        <translation>机器人</translation>
    </message>
    <message>
        <source>link</source>
        <translation>链路</translation>
    </message>
    <message>
        <source>alarm</source>
        <translation>报警</translation>
    </message>
    <message>
        <source>meter</source>
        <translation>仪表</translation>
    </message>
    <message>
        <source>alarms</source>
        <translation>报警系统</translation>
    </message>
    <message>
        <source>control</source>
        <translation>控制</translation>
    </message>
    <message>
        <source>replay</source>
        <translation>回放</translation>
    </message>
</context>
<context>
    <name>Freshness</name>
    <message>
        <source>{s} s ago</source>
        <translation>{s} s 前</translation>
    </message>
    <message>
        <source>{min} min ago</source>
        <translation>{min} min 前</translation>
    </message>
    <message>
        <source>{h} h {min} min ago</source>
        <translation>{h} h {min} min 前</translation>
    </message>
    <message>
        <source>last known {time}, {age}</source>
        <translation>最后已知 {time}，{age}</translation>
    </message>
    <message>
        <source>pose —</source>
        <translation>位姿 —</translation>
    </message>
    <message>
        <source>pose {x}, {y} · {age}</source>
        <translation>位姿 {x}, {y} · {age}</translation>
    </message>
</context>
<context>
    <name>GasStage</name>
    <message>
        <source>A1</source>
        <translation>A1</translation>
    </message>
    <message>
        <source>A2</source>
        <translation>A2</translation>
    </message>
    <message>
        <source>over-range</source>
        <translation>超量程</translation>
    </message>
    <message>
        <source>fault</source>
        <translation>故障</translation>
    </message>
</context>
<context>
    <name>Gateway</name>
    <message>
        <source>sent</source>
        <translation>已发送</translation>
    </message>
    <message>
        <source>refused</source>
        <translation>被拒绝</translation>
    </message>
    <message>
        <source>not delivered</source>
        <translation>未送达</translation>
    </message>
    <message>
        <source>replay is view-only</source>
        <translation>回放仅供查看</translation>
    </message>
    <message>
        <source>no link</source>
        <translation>无链路</translation>
    </message>
    <message>
        <source>link down</source>
        <translation>链路断开</translation>
    </message>
</context>
<context>
    <name>HistoryView</name>
    <message>
        <source>From / to</source>
        <translation>起止时间</translation>
    </message>
    <message>
        <source>Range of the recording to show</source>
        <translation>要显示的记录范围</translation>
    </message>
    <message>
        <source>Show</source>
        <translation>显示</translation>
    </message>
    <message>
        <source>Load the chosen range (Enter)</source>
        <translation>载入所选范围（Enter）</translation>
    </message>
    <message>
        <source>Export CSV…</source>
        <translation>导出 CSV…</translation>
    </message>
    <message>
        <source>Export the visible range of the shown channels</source>
        <translation>导出所显示通道的可见范围</translation>
    </message>
    <message>
        <source>Export from/to…</source>
        <translation>按起止时间导出…</translation>
    </message>
    <message>
        <source>Export the from/to range of the shown channels</source>
        <translation>按起止时间导出所显示通道</translation>
    </message>
    <message>
        <source>from</source>
        <translation>从</translation>
    </message>
    <message>
        <source>to</source>
        <translation>到</translation>
    </message>
    <message>
        <source>Time (UTC)</source>
        <translation>时间（UTC）</translation>
    </message>
    <message>
        <source>Kind</source>
        <translation>类型</translation>
    </message>
    <message>
        <source>Source</source>
        <translation>来源</translation>
    </message>
    <message>
        <source>What</source>
        <translation>内容</translation>
    </message>
    <message>
        <source>exported {t0} – {t1}</source>
        <translation>已导出 {t0} – {t1}</translation>
    </message>
    <message>
        <source>Export CSV</source>
        <translation>导出 CSV</translation>
    </message>
    <message>
        <source>CSV files (*.csv)</source>
        <translation>CSV 文件 (*.csv)</translation>
    </message>
    <message>
        <source>export failed: {why}</source>
        <translation>导出失败：{why}</translation>
    </message>
    <message>
        <source>loading…</source>
        <translation>载入中…</translation>
    </message>
    <message>
        <source>{n} channel(s), {points} points</source>
        <translation>{n} 个通道，{points} 个数据点</translation>
    </message>
    <message>
        <source>Last hour</source>
        <translation>最近一小时</translation>
    </message>
    <message>
        <source>Last shift (8 h)</source>
        <translation>最近一班（8 h）</translation>
    </message>
    <message>
        <source>Last day</source>
        <translation>最近一天</translation>
    </message>
</context>
<context>
    <name>HistoryWindow</name>
    <message>
        <source>Station Patrol — history</source>
        <translation>场站巡检 — 历史数据</translation>
    </message>
    <message>
        <source>Export CSV…</source>
        <translation>导出 CSV…</translation>
    </message>
    <message>
        <source>Close</source>
        <translation>关闭</translation>
    </message>
    <message>
        <source>Session</source>
        <translation>会话</translation>
    </message>
    <message>
        <source>Session: </source>
        <translation>会话：</translation>
    </message>
    <message>
        <source>all sessions mixed (desks and robots not told apart)</source>
        <translation>全部会话混合（不区分操作台和机器人）</translation>
    </message>
    <message>
        <source>Station Patrol — history of {which}</source>
        <translation>场站巡检 — 历史数据：{which}</translation>
    </message>
</context>
<context>
    <name>LinkState</name>
    <message>
        <source>disconnected</source>
        <translation>未连接</translation>
    </message>
    <message>
        <source>connecting</source>
        <translation>连接中</translation>
    </message>
    <message>
        <source>connected</source>
        <translation>已连接</translation>
    </message>
    <message>
        <source>lost</source>
        <translation>中断</translation>
    </message>
    <message>
        <source>reconnecting</source>
        <translation>重连中</translation>
    </message>
    <message>
        <source>replay</source>
        <translation>回放</translation>
    </message>
</context>
<context>
    <name>Localisation</name>
    <message>
        <source>Localisation: — (the robot sends no quality)</source>
        <translation>定位：—（机器人未上报定位质量）</translation>
    </message>
    <message>
        <source>Localisation: LOST — drag Set pose on the map ({sig})</source>
        <translation>定位：丢失 — 请在地图上拖动“设置位姿”（{sig}）</translation>
    </message>
    <message>
        <source>Localisation: odometry only · {sig}</source>
        <translation>定位：仅里程计 · {sig}</translation>
    </message>
    <message>
        <source>Localisation: tracking · match {match} % (rms {rms} cm) · {sig}</source>
        <translation>定位：跟踪中 · 匹配 {match} %（rms {rms} cm）· {sig}</translation>
    </message>
</context>
<context>
    <name>MainWindow</name>
    <message>
        <source>The robot&apos;s own odometry estimate</source>
        <translation>机器人自身的里程计估计</translation>
    </message>
    <message>
        <source>Station Patrol</source>
        <translation>场站巡检机器人监控台</translation>
    </message>
    <message>
        <source>Camera</source>
        <translation>摄像头</translation>
    </message>
    <message>
        <source>Map</source>
        <translation>地图</translation>
    </message>
    <message>
        <source>{name} requested</source>
        <translation>已请求 {name}</translation>
    </message>
    <message>
        <source>Meters</source>
        <translation>仪表</translation>
    </message>
    <message>
        <source>Environment</source>
        <translation>环境</translation>
    </message>
    <message>
        <source>Control</source>
        <translation>控制</translation>
    </message>
    <message>
        <source>Alarms and events</source>
        <translation>报警与事件</translation>
    </message>
    <message>
        <source>The autonomous patrol, as the robot last reported it (F7 resumes a paused patrol from any tab)</source>
        <translation>机器人最近报告的自主巡检状态（任意标签页按 F7 可恢复暂停的巡检）</translation>
    </message>
    <message>
        <source>link disconnected</source>
        <translation>链路未连接</translation>
    </message>
    <message>
        <source>pose —</source>
        <translation>位姿 —</translation>
    </message>
    <message>
        <source>RTT — ms</source>
        <translation>往返时延 — ms</translation>
    </message>
    <message>
        <source>dropped {n}</source>
        <translation>丢弃 {n}</translation>
    </message>
    <message>
        <source>{rate} msg/s</source>
        <translation>{rate} 条/s</translation>
    </message>
    <message>
        <source>malformed {n}</source>
        <translation>格式错误 {n}</translation>
    </message>
    <message>
        <source>refused 0 · tel lost 0</source>
        <translation>拒收 0 · 遥测丢失 0</translation>
    </message>
    <message>
        <source>control —</source>
        <translation>控制 —</translation>
    </message>
    <message>
        <source>{name} {outcome}: {why}</source>
        <translation>{name} {outcome}：{why}</translation>
    </message>
    <message>
        <source>replay is view-only: resume not sent</source>
        <translation>回放仅供查看：未发送恢复指令</translation>
    </message>
    <message>
        <source>no link to the robot: resume not sent</source>
        <translation>与机器人无链路：未发送恢复指令</translation>
    </message>
    <message>
        <source>no paused patrol to resume (patrol {state})</source>
        <translation>没有可恢复的暂停巡检（巡检 {state}）</translation>
    </message>
    <message>
        <source>resume_patrol requested (F7)</source>
        <translation>已请求恢复巡检（F7）</translation>
    </message>
    <message>
        <source>replay is view-only: no e-stop sent</source>
        <translation>回放仅供查看：未发送急停</translation>
    </message>
    <message>
        <source>EMERGENCY STOP pressed</source>
        <translation>已按下急停</translation>
    </message>
    <message>
        <source>e-stop reset requested</source>
        <translation>已请求急停复位</translation>
    </message>
    <message>
        <source>command {seq} refused: {reason}</source>
        <translation>指令 {seq} 被拒绝：{reason}</translation>
    </message>
    <message>
        <source>mode {mode}</source>
        <translation>模式 {mode}</translation>
    </message>
    <message>
        <source>alarm settings changed</source>
        <translation>报警设置已更改</translation>
    </message>
    <message>
        <source>link {state}</source>
        <translation>链路{state}</translation>
    </message>
    <message>
        <source>Link restored</source>
        <translation>链路已恢复</translation>
    </message>
    <message>
        <source>link restored</source>
        <translation>链路已恢复</translation>
    </message>
    <message>
        <source>control: no link</source>
        <translation>控制：无链路</translation>
    </message>
    <message>
        <source>RTT {ms} ms</source>
        <translation>往返时延 {ms} ms</translation>
    </message>
    <message>
        <source>desk decoder refused: </source>
        <translation>操作台解码器拒收：</translation>
    </message>
    <message>
        <source>frames the decoder dropped or could not decode: {n}
camera frames replaced by a newer one before shown: {stale}</source>
        <translation>解码器丢弃或无法解码的帧：{n}
显示前被更新帧替换的图像帧：{stale}</translation>
    </message>
    <message>
        <source>Layout reset</source>
        <translation>布局已重置</translation>
    </message>
    <message>
        <source>Language</source>
        <translation>语言</translation>
    </message>
    <message>
        <source>Language: {name} from the next start of the desk</source>
        <translation>语言：{name}，下次启动操作台时生效</translation>
    </message>
    <message>
        <source>&amp;Robot</source>
        <translation>机器人(&amp;R)</translation>
    </message>
    <message>
        <source>EMERGENCY STOP	Esc / F1</source>
        <translation>急停	Esc / F1</translation>
    </message>
    <message>
        <source>Stop	Space</source>
        <translation>停止	Space</translation>
    </message>
    <message>
        <source>Reset e-stop	Ctrl+Shift+R</source>
        <translation>急停复位	Ctrl+Shift+R</translation>
    </message>
    <message>
        <source>Faster	+</source>
        <translation>加速	+</translation>
    </message>
    <message>
        <source>Slower	-</source>
        <translation>减速	-</translation>
    </message>
    <message>
        <source>Resume patrol</source>
        <translation>恢复巡检</translation>
    </message>
    <message>
        <source>&amp;View</source>
        <translation>视图(&amp;V)</translation>
    </message>
    <message>
        <source>Plot window {minutes} min</source>
        <translation>曲线窗口 {minutes} min</translation>
    </message>
    <message>
        <source>Reset layout</source>
        <translation>重置布局</translation>
    </message>
    <message>
        <source>Window size, panel sizes and plot window as when first started</source>
        <translation>窗口大小、面板大小和曲线时间窗恢复为首次启动时的状态</translation>
    </message>
    <message>
        <source>Full screen</source>
        <translation>全屏</translation>
    </message>
    <message>
        <source>&amp;Alarms</source>
        <translation>报警(&amp;A)</translation>
    </message>
    <message>
        <source>Alarm settings…</source>
        <translation>报警设置…</translation>
    </message>
    <message>
        <source>Show log folder</source>
        <translation>打开日志文件夹</translation>
    </message>
    <message>
        <source>Quit</source>
        <translation>退出</translation>
    </message>
    <message>
        <source>&amp;File</source>
        <translation>文件(&amp;F)</translation>
    </message>
    <message>
        <source>OPC UA server not started: {why}</source>
        <translation>OPC UA 服务器未启动：{why}</translation>
    </message>
</context>
<context>
    <name>MapModel</name>
    <message>
        <source>Patrol: —</source>
        <translation>巡检：—</translation>
    </message>
    <message>
        <source> · route {route}</source>
        <translation> · 路线 {route}</translation>
    </message>
    <message>
        <source>Patrol: paused by operator — {key} resumes</source>
        <translation>巡检：已被操作员暂停 — 按 {key} 恢复</translation>
    </message>
    <message>
        <source>Patrol: paused{why} — {key} resumes</source>
        <translation>巡检：已暂停{why} — 按 {key} 恢复</translation>
    </message>
    <message>
        <source>Patrol: {state}</source>
        <translation>巡检：{state}</translation>
    </message>
</context>
<context>
    <name>MapPanel</name>
    <message>
        <source>No link to the robot: patrol commands are off until it answers again.</source>
        <translation>与机器人无链路：机器人恢复应答前，巡检指令不可用。</translation>
    </message>
    <message>
        <source>Patrol: —</source>
        <translation>巡检：—</translation>
    </message>
    <message>
        <source>Route: —</source>
        <translation>路线：—</translation>
    </message>
    <message>
        <source>Start</source>
        <translation>开始</translation>
    </message>
    <message>
        <source>Pause</source>
        <translation>暂停</translation>
    </message>
    <message>
        <source>Resume</source>
        <translation>恢复</translation>
    </message>
    <message>
        <source>Abort</source>
        <translation>中止</translation>
    </message>
    <message>
        <source>Dock</source>
        <translation>回充</translation>
    </message>
    <message>
        <source>Go to</source>
        <translation>前往</translation>
    </message>
    <message>
        <source>Set pose</source>
        <translation>设置位姿</translation>
    </message>
    <message>
        <source>Arm: the next click on the map sends the robot there</source>
        <translation>待命：下一次在地图上点击，机器人将前往该处</translation>
    </message>
    <message>
        <source>Arm: press on the map where the robot is, drag the way it faces, release</source>
        <translation>启用：在地图上按下机器人所在位置，向其朝向拖动，然后松开</translation>
    </message>
    <message>
        <source>point</source>
        <translation>巡检点</translation>
    </message>
    <message>
        <source>kind</source>
        <translation>类型</translation>
    </message>
    <message>
        <source>state</source>
        <translation>状态</translation>
    </message>
    <message>
        <source>Go to selected point</source>
        <translation>前往所选点</translation>
    </message>
    <message>
        <source>Name of the saved map (letters, digits, &apos;-&apos; or &apos;_&apos;)</source>
        <translation>保存的地图名称（字母、数字、&apos;-&apos; 或 &apos;_&apos;）</translation>
    </message>
    <message>
        <source>Start mapping</source>
        <translation>开始建图</translation>
    </message>
    <message>
        <source>Save map</source>
        <translation>保存地图</translation>
    </message>
    <message>
        <source>Stop mapping</source>
        <translation>停止建图</translation>
    </message>
    <message>
        <source>Patrol</source>
        <translation>巡检</translation>
    </message>
    <message>
        <source>Route editor</source>
        <translation>路线编辑器</translation>
    </message>
    <message>
        <source>Mapping</source>
        <translation>建图</translation>
    </message>
    <message>
        <source>Fit map  (Ctrl+0)</source>
        <translation>适应地图  (Ctrl+0)</translation>
    </message>
    <message>
        <source>Map not shown: {why}</source>
        <translation>无法显示地图：{why}</translation>
    </message>
    <message>
        <source>Replay: view only, no commands are sent.</source>
        <translation>回放：仅供查看，不发送任何指令。</translation>
    </message>
    <message>
        <source>No link to the robot: {name} not sent.</source>
        <translation>与机器人无链路：未发送 {name}。</translation>
    </message>
    <message>
        <source>Replay: view only, {name} not sent.</source>
        <translation>回放：仅供查看，未发送 {name}。</translation>
    </message>
    <message>
        <source>sent {name}</source>
        <translation>已发送 {name}</translation>
    </message>
    <message>
        <source>Route not valid; see the route editor.</source>
        <translation>路线无效；请查看路线编辑器。</translation>
    </message>
    <message>
        <source>sent goto x {x} m, y {y} m</source>
        <translation>已发送前往 x {x} m, y {y} m</translation>
    </message>
    <message>
        <source>Select a point in the list first.</source>
        <translation>请先在列表中选择一个点。</translation>
    </message>
    <message>
        <source>x {x} m, y {y} m — arm Go to ({key}) to send the robot there</source>
        <translation>x {x} m, y {y} m — 启用“前往”（{key}）可让机器人前往该处</translation>
    </message>
    <message>
        <source>Go to: click the map where the robot should go.</source>
        <translation>前往：在地图上点击机器人要去的位置。</translation>
    </message>
    <message>
        <source>Add by click: each click on the map adds a point.</source>
        <translation>点击添加：每次在地图上点击添加一个点。</translation>
    </message>
    <message>
        <source>Patrol: {state}</source>
        <translation>巡检：{state}</translation>
    </message>
    <message>
        <source>  ·  local planner {name}</source>
        <translation>  ·  局部规划器 {name}</translation>
    </message>
    <message>
        <source>Route: {route}</source>
        <translation>路线：{route}</translation>
    </message>
    <message>
        <source>Start a patrol on route &apos;{name}&apos;</source>
        <translation>按路线“{name}”开始巡检</translation>
    </message>
    <message>
        <source>Start a patrol on the robot&apos;s default route</source>
        <translation>按机器人默认路线开始巡检</translation>
    </message>
</context>
<context>
    <name>MapView</name>
    <message>
        <source>Fit map</source>
        <translation>适应地图</translation>
    </message>
</context>
<context>
    <name>MeterModel</name>
    <message>
        <source>{label} no reading: {why}</source>
        <translation>{label} 无读数：{why}</translation>
    </message>
    <message>
        <source>route not used for meter profiles: {why}</source>
        <translation>路线未用于仪表参数：{why}</translation>
    </message>
    <message>
        <source>reference not prepared: {why}</source>
        <translation>参考帧未能预先测量：{why}</translation>
    </message>
</context>
<context>
    <name>MeterPanel</name>
    <message>
        <source>Read meter</source>
        <translation>读取仪表</translation>
    </message>
    <message>
        <source>Aim the camera at the chosen gauge and read it</source>
        <translation>将摄像头对准所选仪表并读数</translation>
    </message>
    <message>
        <source>Calibrate…</source>
        <translation>标定…</translation>
    </message>
    <message>
        <source>Make a gauge profile, or calibrate an inspection point of the route, on the current frame</source>
        <translation>在当前画面上制作仪表参数，或标定路线上的巡检点</translation>
    </message>
    <message>
        <source>idle</source>
        <translation>空闲</translation>
    </message>
    <message>
        <source>Gauge</source>
        <translation>仪表</translation>
    </message>
    <message>
        <source>Point</source>
        <translation>巡检点</translation>
    </message>
    <message>
        <source>Value</source>
        <translation>读数</translation>
    </message>
    <message>
        <source>Unit</source>
        <translation>单位</translation>
    </message>
    <message>
        <source>Normal band</source>
        <translation>正常范围</translation>
    </message>
    <message>
        <source>State</source>
        <translation>状态</translation>
    </message>
    <message>
        <source>Confidence</source>
        <translation>置信度</translation>
    </message>
    <message>
        <source>Time</source>
        <translation>时间</translation>
    </message>
    <message>
        <source>Note</source>
        <translation>备注</translation>
    </message>
    <message>
        <source>calibrated point</source>
        <translation>已标定点</translation>
    </message>
    <message>
        <source>no frame to calibrate on yet</source>
        <translation>尚无可用于标定的画面</translation>
    </message>
</context>
<context>
    <name>MeterState</name>
    <message>
        <source>normal</source>
        <translation>正常</translation>
    </message>
    <message>
        <source>out of band</source>
        <translation>超出正常范围</translation>
    </message>
    <message>
        <source>no reading</source>
        <translation>无读数</translation>
    </message>
</context>
<context>
    <name>Meters</name>
    <message>
        <source>reading {gauge}: {n}/{wanted} frames</source>
        <translation>正在读取 {gauge}：{n}/{wanted} 帧</translation>
    </message>
    <message>
        <source>reading {gauge} …</source>
        <translation>正在读取 {gauge} …</translation>
    </message>
    <message>
        <source>{gauge}: no reading ({why})</source>
        <translation>{gauge}：无读数（{why}）</translation>
    </message>
    <message>
        <source>meter {gauge}: no reading ({why})</source>
        <translation>仪表 {gauge}：无读数（{why}）</translation>
    </message>
    <message>
        <source>{gauge}: {value} {unit} (confidence {conf})</source>
        <translation>{gauge}：{value} {unit}（置信度 {conf}）</translation>
    </message>
    <message>
        <source>meter {gauge} at {point}: {value} {unit}, {state} (confidence {conf})</source>
        <translation>仪表 {gauge}（{point}）：{value} {unit}，{state}（置信度 {conf}）</translation>
    </message>
</context>
<context>
    <name>OpcUa</name>
    <message>
        <source>OPC UA: ANONYMOUS ACCESS ON</source>
        <translation>OPC UA：匿名访问已开启</translation>
    </message>
    <message>
        <source>OPC UA: SECURITY NONE ON</source>
        <translation>OPC UA：未启用安全策略</translation>
    </message>
</context>
<context>
    <name>OutOfServiceDialog</name>
    <message>
        <source>Alarm out of service</source>
        <translation>停用报警</translation>
    </message>
    <message>
        <source>why (required), e.g. gas sensor replaced, work order 4711</source>
        <translation>原因（必填），例如：更换燃气传感器，工单 4711</translation>
    </message>
    <message>
        <source>It will not be shown until put back in service.</source>
        <translation>恢复投用前将不再显示。</translation>
    </message>
    <message>
        <source>Reason</source>
        <translation>原因</translation>
    </message>
</context>
<context>
    <name>PatrolState</name>
    <message>
        <source>idle</source>
        <translation>空闲</translation>
    </message>
    <message>
        <source>planning</source>
        <translation>规划中</translation>
    </message>
    <message>
        <source>driving</source>
        <translation>行驶中</translation>
    </message>
    <message>
        <source>avoiding</source>
        <translation>避障中</translation>
    </message>
    <message>
        <source>inspecting</source>
        <translation>巡检中</translation>
    </message>
    <message>
        <source>paused</source>
        <translation>已暂停</translation>
    </message>
    <message>
        <source>docking</source>
        <translation>回充中</translation>
    </message>
    <message>
        <source>done</source>
        <translation>已完成</translation>
    </message>
    <message>
        <source>aborted</source>
        <translation>已中止</translation>
    </message>
    <message>
        <source>failed</source>
        <translation>失败</translation>
    </message>
    <message>
        <source>pending</source>
        <translation>待巡检</translation>
    </message>
    <message>
        <source>current</source>
        <translation>当前</translation>
    </message>
    <message>
        <source>skipped</source>
        <translation>已跳过</translation>
    </message>
    <message>
        <source>meter</source>
        <translation>仪表</translation>
    </message>
    <message>
        <source>valve</source>
        <translation>阀门</translation>
    </message>
    <message>
        <source>waypoint</source>
        <translation>路径点</translation>
    </message>
    <message>
        <source>tank_wall</source>
        <translation>罐壁</translation>
    </message>
    <message>
        <source>operator</source>
        <translation>操作员</translation>
    </message>
    <message>
        <source>estop</source>
        <translation>急停</translation>
    </message>
    <message>
        <source>dock requested</source>
        <translation>已请求回充</translation>
    </message>
    <message>
        <source>running</source>
        <translation>运行中</translation>
    </message>
    <message>
        <source>default</source>
        <translation>默认</translation>
    </message>
    <message>
        <source>operator took over (drive)</source>
        <translation>操作员接管（手动驾驶）</translation>
    </message>
    <message>
        <source>operator stop</source>
        <translation>操作员停车</translation>
    </message>
</context>
<context>
    <name>Priority</name>
    <message>
        <source>EMERGENCY</source>
        <translation>紧急</translation>
    </message>
    <message>
        <source>HIGH</source>
        <translation>高</translation>
    </message>
    <message>
        <source>MEDIUM</source>
        <translation>中</translation>
    </message>
    <message>
        <source>LOW</source>
        <translation>低</translation>
    </message>
</context>
<context>
    <name>Refusals</name>
    <message>
        <source>nothing refused</source>
        <translation>无拒收</translation>
    </message>
    <message>
        <source>desk decoder: </source>
        <translation>操作台解码器：</translation>
    </message>
    <message>
        <source>robot: </source>
        <translation>机器人：</translation>
    </message>
    <message>
        <source>telemetry lost {lost}, late or repeated {late}</source>
        <translation>遥测丢失 {lost}，迟到或重复 {late}</translation>
    </message>
    <message>
        <source>refused {n} · tel lost {lost}</source>
        <translation>拒收 {n} · 遥测丢失 {lost}</translation>
    </message>
</context>
<context>
    <name>Replay</name>
    <message>
        <source>REPLAY {time} ×{speed} — view only (UTC)</source>
        <translation>回放 {time} ×{speed} — 仅供查看（UTC）</translation>
    </message>
    <message>
        <source> — replay (view only)</source>
        <translation> — 回放（仅供查看）</translation>
    </message>
    <message>
        <source>replay is view-only: {what} not sent</source>
        <translation>回放仅供查看：未发送 {what}</translation>
    </message>
    <message>
        <source>Station Patrol — replay of {which}</source>
        <translation>场站巡检 — 回放：{which}</translation>
    </message>
</context>
<context>
    <name>ReplayBar</name>
    <message>
        <source>Replay</source>
        <translation>回放</translation>
    </message>
    <message>
        <source>Play</source>
        <translation>播放</translation>
    </message>
    <message>
        <source>Play / pause (P)</source>
        <translation>播放 / 暂停（P）</translation>
    </message>
    <message>
        <source>−10 s</source>
        <translation>−10 s</translation>
    </message>
    <message>
        <source>Back 10 s (,)</source>
        <translation>后退 10 s（,）</translation>
    </message>
    <message>
        <source>+10 s</source>
        <translation>+10 s</translation>
    </message>
    <message>
        <source>Forward 10 s (.)</source>
        <translation>前进 10 s（.）</translation>
    </message>
    <message>
        <source>Start</source>
        <translation>开始</translation>
    </message>
    <message>
        <source>Drag to seek</source>
        <translation>拖动定位</translation>
    </message>
    <message>
        <source>Replay speed ([ slower, ] faster)</source>
        <translation>回放速度（[ 减慢，] 加快）</translation>
    </message>
    <message>
        <source>Slower</source>
        <translation>减慢</translation>
    </message>
    <message>
        <source>Faster</source>
        <translation>加快</translation>
    </message>
    <message>
        <source>Pause</source>
        <translation>暂停</translation>
    </message>
</context>
<context>
    <name>Report</name>
    <message>
        <source> by {user}</source>
        <translation>（{user}）</translation>
    </message>
    <message>
        <source>acknowledged</source>
        <translation>已确认</translation>
    </message>
    <message>
        <source>shelved</source>
        <translation>已搁置</translation>
    </message>
    <message>
        <source>out of service</source>
        <translation>已停用</translation>
    </message>
    <message>
        <source>still standing at the end of the range</source>
        <translation>时段结束时仍未消除</translation>
    </message>
    <message>
        <source>not acknowledged</source>
        <translation>未确认</translation>
    </message>
    <message>
        <source>The wall inspection&apos;s record does not read: {why}</source>
        <translation>无法读取罐壁检测记录：{why}</translation>
    </message>
    <message>
        <source>Combustible gas</source>
        <translation>可燃气体浓度</translation>
    </message>
    <message>
        <source>Temperature</source>
        <translation>温度</translation>
    </message>
    <message>
        <source>Humidity</source>
        <translation>湿度</translation>
    </message>
    <message>
        <source>Battery</source>
        <translation>电池电压</translation>
    </message>
    <message>
        <source>Obstacle ahead</source>
        <translation>前方障碍物距离</translation>
    </message>
    <message>
        <source>Patrol report</source>
        <translation>巡检报告</translation>
    </message>
    <message>
        <source>Station patrol report</source>
        <translation>场站巡检报告</translation>
    </message>
    <message>
        <source>From {t0} to {t1} UTC</source>
        <translation>时段：{t0} 至 {t1}（UTC）</translation>
    </message>
    <message>
        <source>made {t} UTC</source>
        <translation>生成于 {t}（UTC）</translation>
    </message>
    <message>
        <source> from {source}</source>
        <translation>，数据来源 {source}</translation>
    </message>
    <message>
        <source>Distance driven</source>
        <translation>行驶里程</translation>
    </message>
    <message>
        <source>Meter readings</source>
        <translation>仪表读数</translation>
    </message>
    <message>
        <source>Alarms</source>
        <translation>报警</translation>
    </message>
    <message>
        <source>Not acknowledged</source>
        <translation>未确认</translation>
    </message>
    <message>
        <source>Operator commands</source>
        <translation>操作指令</translation>
    </message>
    <message>
        <source>Events</source>
        <translation>事件</translation>
    </message>
    <message>
        <source>Route</source>
        <translation>巡检路线</translation>
    </message>
    <message>
        <source>Inspection points: </source>
        <translation>巡检点：</translation>
    </message>
    <message>
        <source>No meter readings in this range.</source>
        <translation>该时段内无仪表读数。</translation>
    </message>
    <message>
        <source>Time (UTC)</source>
        <translation>时间（UTC）</translation>
    </message>
    <message>
        <source>Point</source>
        <translation>巡检点</translation>
    </message>
    <message>
        <source>Value</source>
        <translation>读数</translation>
    </message>
    <message>
        <source>Confidence</source>
        <translation>置信度</translation>
    </message>
    <message>
        <source>State</source>
        <translation>状态</translation>
    </message>
    <message>
        <source>Snapshot</source>
        <translation>抓拍图像</translation>
    </message>
    <message>
        <source>not read</source>
        <translation>未读取</translation>
    </message>
    <message>
        <source>reference</source>
        <translation>参考图像</translation>
    </message>
    <message>
        <source>now</source>
        <translation>本次</translation>
    </message>
    <message>
        <source>Alarms and their handling</source>
        <translation>报警及处置</translation>
    </message>
    <message>
        <source>No alarms in this range.</source>
        <translation>该时段内无报警。</translation>
    </message>
    <message>
        <source>Alarm</source>
        <translation>报警</translation>
    </message>
    <message>
        <source>Priority</source>
        <translation>优先级</translation>
    </message>
    <message>
        <source>Raised</source>
        <translation>报警时间</translation>
    </message>
    <message>
        <source>Value / limit</source>
        <translation>数值 / 限值</translation>
    </message>
    <message>
        <source>Acknowledged</source>
        <translation>确认</translation>
    </message>
    <message>
        <source>Cleared</source>
        <translation>消除时间</translation>
    </message>
    <message>
        <source>Handling</source>
        <translation>处置情况</translation>
    </message>
    <message>
        <source>Environment</source>
        <translation>环境监测</translation>
    </message>
    <message>
        <source>No telemetry in this range.</source>
        <translation>该时段内无遥测数据。</translation>
    </message>
    <message>
        <source>Channel</source>
        <translation>通道</translation>
    </message>
    <message>
        <source>Min</source>
        <translation>最小值</translation>
    </message>
    <message>
        <source>Max</source>
        <translation>最大值</translation>
    </message>
    <message>
        <source>Mean</source>
        <translation>平均值</translation>
    </message>
    <message>
        <source>Samples</source>
        <translation>样本数</translation>
    </message>
    <message>
        <source>normal</source>
        <translation>正常</translation>
    </message>
    <message>
        <source>out of band</source>
        <translation>超出正常范围</translation>
    </message>
    <message>
        <source>no reading</source>
        <translation>无读数</translation>
    </message>
    <message>
        <source>ok</source>
        <translation>正常</translation>
    </message>
    <message>
        <source>high</source>
        <translation>偏高</translation>
    </message>
    <message>
        <source>low</source>
        <translation>偏低</translation>
    </message>
    <message>
        <source>alarm</source>
        <translation>报警</translation>
    </message>
    <message>
        <source>warning</source>
        <translation>警告</translation>
    </message>
    <message>
        <source>unreadable</source>
        <translation>无法读取</translation>
    </message>
    <message>
        <source>EMERGENCY</source>
        <translation>紧急</translation>
    </message>
    <message>
        <source>HIGH</source>
        <translation>高</translation>
    </message>
    <message>
        <source>MEDIUM</source>
        <translation>中</translation>
    </message>
    <message>
        <source>LOW</source>
        <translation>低</translation>
    </message>
    <message>
        <source>no data</source>
        <translation>无数据</translation>
    </message>
    <message>
        <source>no route recorded</source>
        <translation>未记录路线</translation>
    </message>
    <message>
        <source>The unrolled wall (x round the tank from the shell&apos;s seam, y up): thickness from red (at or below the limit) to green (nominal); dark: obstacles; grey-green: covered, no reading.</source>
        <translation>罐壁展开图（x 为自壳体焊缝起沿罐周方向，y 向上）：壁厚由红色（等于或低于限值）渐变至绿色（公称厚度）；深色：障碍物；灰绿色：已覆盖、无读数。</translation>
    </message>
    <message>
        <source>Wall inspection</source>
        <translation>罐壁检测</translation>
    </message>
    <message>
        <source>Wall {name}: {cols} × {rows} cells of {cell} mm, nominal {nominal} mm, limit {limit} mm; inspection {state}.</source>
        <translation>罐壁 {name}：{cols} × {rows} 个单元，单元 {cell} mm，公称壁厚 {nominal} mm，限值 {limit} mm；检测{state}。</translation>
    </message>
    <message>
        <source>Coverage</source>
        <translation>覆盖率</translation>
    </message>
    <message>
        <source>Repetition</source>
        <translation>重复率</translation>
    </message>
    <message>
        <source>Readings</source>
        <translation>读数数量</translation>
    </message>
    <message>
        <source>Cells measured</source>
        <translation>已测单元</translation>
    </message>
    <message>
        <source>Cells below the limit</source>
        <translation>低于限值的单元</translation>
    </message>
    <message>
        <source>Thickness</source>
        <translation>壁厚</translation>
    </message>
    <message>
        <source>x round (m)</source>
        <translation>x 环向 (m)</translation>
    </message>
    <message>
        <source>y up (m)</source>
        <translation>y 向上 (m)</translation>
    </message>
    <message>
        <source>Cell (row, col)</source>
        <translation>单元（行, 列）</translation>
    </message>
    <message>
        <source>No thickness readings.</source>
        <translation>无壁厚读数。</translation>
    </message>
</context>
<context>
    <name>ReviewActions</name>
    <message>
        <source>report failed: {why}</source>
        <translation>报告生成失败：{why}</translation>
    </message>
    <message>
        <source>Re&amp;view</source>
        <translation>回顾(&amp;V)</translation>
    </message>
    <message>
        <source>History…</source>
        <translation>历史数据…</translation>
    </message>
    <message>
        <source>Replay the last hour…</source>
        <translation>回放最近一小时…</translation>
    </message>
    <message>
        <source>Patrol report (last 24 h)…</source>
        <translation>巡检报告（最近 24 h）…</translation>
    </message>
    <message>
        <source>no archive at {path}</source>
        <translation>{path} 处没有档案</translation>
    </message>
    <message>
        <source>cannot open the archive: {why}</source>
        <translation>无法打开档案：{why}</translation>
    </message>
    <message>
        <source>the archive holds no recording yet</source>
        <translation>档案中尚无记录</translation>
    </message>
    <message>
        <source>this window cannot open a replay</source>
        <translation>此窗口无法打开回放</translation>
    </message>
    <message>
        <source>Patrol report</source>
        <translation>巡检报告</translation>
    </message>
    <message>
        <source>PDF (*.pdf);;HTML (*.html)</source>
        <translation>PDF (*.pdf);;HTML (*.html)</translation>
    </message>
    <message>
        <source>gathering the report…</source>
        <translation>正在汇总报告…</translation>
    </message>
    <message>
        <source>report written: {path}</source>
        <translation>报告已写入：{path}</translation>
    </message>
</context>
<context>
    <name>RobotMode</name>
    <message>
        <source>IDLE</source>
        <translation>空闲</translation>
    </message>
    <message>
        <source>TELEOP</source>
        <translation>遥控</translation>
    </message>
    <message>
        <source>PATROL</source>
        <translation>巡检</translation>
    </message>
    <message>
        <source>ESTOP</source>
        <translation>急停</translation>
    </message>
    <message>
        <source>FAILSAFE</source>
        <translation>失效保护</translation>
    </message>
    <message>
        <source>DOCKED</source>
        <translation>已停靠充电</translation>
    </message>
</context>
<context>
    <name>RouteEditor</name>
    <message>
        <source>name</source>
        <translation>名称</translation>
    </message>
    <message>
        <source>kind</source>
        <translation>类型</translation>
    </message>
    <message>
        <source>gauge</source>
        <translation>仪表</translation>
    </message>
    <message>
        <source>dwell s</source>
        <translation>停留 s</translation>
    </message>
    <message>
        <source>route</source>
        <translation>路线</translation>
    </message>
    <message>
        <source>Route name…</source>
        <translation>路线名称…</translation>
    </message>
    <message>
        <source>Add by click</source>
        <translation>点击添加</translation>
    </message>
    <message>
        <source>While on, a click on the map adds a point there</source>
        <translation>开启时，在地图上点击即在该处添加点</translation>
    </message>
    <message>
        <source>Remove</source>
        <translation>删除</translation>
    </message>
    <message>
        <source>Up</source>
        <translation>上移</translation>
    </message>
    <message>
        <source>Down</source>
        <translation>下移</translation>
    </message>
    <message>
        <source>Rename…</source>
        <translation>重命名…</translation>
    </message>
    <message>
        <source>Gauge…</source>
        <translation>仪表…</translation>
    </message>
    <message>
        <source> s</source>
        <translation> s</translation>
    </message>
    <message>
        <source>Open…</source>
        <translation>打开…</translation>
    </message>
    <message>
        <source>Save…</source>
        <translation>保存…</translation>
    </message>
    <message>
        <source>New</source>
        <translation>新建</translation>
    </message>
    <message>
        <source>Start patrol with this route</source>
        <translation>按此路线开始巡检</translation>
    </message>
    <message>
        <source>A point needs a name.</source>
        <translation>巡检点需要名称。</translation>
    </message>
    <message>
        <source>There is already a point named {name}.</source>
        <translation>已存在名为 {name} 的点。</translation>
    </message>
    <message>
        <source>New route: click the map in &apos;Add by click&apos; mode to add points.</source>
        <translation>新路线：在“点击添加”模式下点击地图添加点。</translation>
    </message>
    <message>
        <source>Could not open the route: {why}</source>
        <translation>无法打开路线：{why}</translation>
    </message>
    <message>
        <source>Opened {file}: {n} points.</source>
        <translation>已打开 {file}：{n} 个点。</translation>
    </message>
    <message>
        <source>Could not save the route: {why}</source>
        <translation>无法保存路线：{why}</translation>
    </message>
    <message>
        <source> {n} calibrated point(s) name profiles beside {old}; copy its .points folder too, or calibrate them again.</source>
        <translation> 有 {n} 个已标定点引用 {old} 旁的参数文件；请一并复制其 .points 文件夹，或重新标定。</translation>
    </message>
    <message>
        <source>Saved {file}.</source>
        <translation>已保存 {file}。</translation>
    </message>
    <message>
        <source>The route is not ready: {why}</source>
        <translation>路线尚未就绪：{why}</translation>
    </message>
    <message>
        <source>Rename point</source>
        <translation>重命名巡检点</translation>
    </message>
    <message>
        <source>Name:</source>
        <translation>名称：</translation>
    </message>
    <message>
        <source>Gauge</source>
        <translation>仪表</translation>
    </message>
    <message>
        <source>Gauge id (empty: none):</source>
        <translation>仪表编号（留空：无）：</translation>
    </message>
    <message>
        <source>Route name</source>
        <translation>路线名称</translation>
    </message>
    <message>
        <source>Open route</source>
        <translation>打开路线</translation>
    </message>
    <message>
        <source>Routes (*.json);;All files (*)</source>
        <translation>路线 (*.json);;所有文件 (*)</translation>
    </message>
    <message>
        <source>Save route</source>
        <translation>保存路线</translation>
    </message>
    <message>
        <source>Routes (*.json)</source>
        <translation>路线 (*.json)</translation>
    </message>
    <message>
        <source>Route: &lt;b&gt;{name}&lt;/b&gt;</source>
        <translation>路线：&lt;b&gt;{name}&lt;/b&gt;</translation>
    </message>
</context>
<context>
    <name>Session</name>
    <message>
        <source>session 0 (recorded before sessions: desks and robots not told apart)</source>
        <translation>会话 0（会话功能之前的记录：不区分操作台和机器人）</translation>
    </message>
    <message>
        <source>robot {name}</source>
        <translation>机器人 {name}</translation>
    </message>
    <message>
        <source>desk {name}</source>
        <translation>操作台 {name}</translation>
    </message>
    <message>
        <source>from {time} UTC</source>
        <translation>始于 {time} UTC</translation>
    </message>
    <message>
        <source>session {id}</source>
        <translation>会话 {id}</translation>
    </message>
    <message>
        <source>all sessions mixed (desks and robots not told apart)</source>
        <translation>全部会话混合（不区分操作台和机器人）</translation>
    </message>
</context>
<context>
    <name>ShelveDialog</name>
    <message>
        <source>Shelve alarm</source>
        <translation>搁置报警</translation>
    </message>
    <message>
        <source> min</source>
        <translation> min</translation>
    </message>
    <message>
        <source>preset…</source>
        <translation>预设…</translation>
    </message>
    <message>
        <source>why (required), e.g. sensor under maintenance</source>
        <translation>原因（必填），例如：传感器检修中</translation>
    </message>
    <message>
        <source>Shelve for</source>
        <translation>搁置时长</translation>
    </message>
    <message>
        <source>Reason</source>
        <translation>原因</translation>
    </message>
</context>
<context>
    <name>ValueTile</name>
    <message>
        <source>—</source>
        <translation>—</translation>
    </message>
</context>
<context>
    <name>VideoPanel</name>
    <message>
        <source>no video yet</source>
        <translation>暂无视频</translation>
    </message>
    <message>
        <source>— fps</source>
        <translation>— fps</translation>
    </message>
    <message>
        <source>latency — ms</source>
        <translation>延迟 — ms</translation>
    </message>
    <message>
        <source>frame {id}  {w}×{h}</source>
        <translation>帧 {id}  {w}×{h}</translation>
    </message>
    <message>
        <source>latency {ms} ms</source>
        <translation>延迟 {ms} ms</translation>
    </message>
    <message>
        <source>VIDEO STALE</source>
        <translation>视频已过期</translation>
    </message>
    <message>
        <source>video stale</source>
        <translation>视频已过期</translation>
    </message>
</context>
<context>
    <name>Wall</name>
    <message>
        <source>x {x} m round, y {y} m up (cell {row}, {col})</source>
        <translation>环向 x {x} m，向上 y {y} m（单元 {row}, {col}）</translation>
    </message>
    <message>
        <source>Wall {mm} mm, below limit {limit} mm, at {where}</source>
        <translation>罐壁 {mm} mm，低于限值 {limit} mm，位置 {where}</translation>
    </message>
</context>
<context>
    <name>WallPanel</name>
    <message>
        <source>coverage —</source>
        <translation>覆盖率 —</translation>
    </message>
    <message>
        <source>repetition —</source>
        <translation>重复率 —</translation>
    </message>
    <message>
        <source>inspection —</source>
        <translation>检测 —</translation>
    </message>
    <message>
        <source>readings 0</source>
        <translation>读数 0</translation>
    </message>
    <message>
        <source>thinnest —</source>
        <translation>最薄处 —</translation>
    </message>
    <message>
        <source>pose —</source>
        <translation>位姿 —</translation>
    </message>
    <message>
        <source>Start</source>
        <translation>开始</translation>
    </message>
    <message>
        <source>Start the wall inspection</source>
        <translation>开始罐壁检测</translation>
    </message>
    <message>
        <source>Pause</source>
        <translation>暂停</translation>
    </message>
    <message>
        <source>Pause the wall inspection</source>
        <translation>暂停罐壁检测</translation>
    </message>
    <message>
        <source>Resume</source>
        <translation>恢复</translation>
    </message>
    <message>
        <source>Resume the wall inspection</source>
        <translation>恢复罐壁检测</translation>
    </message>
    <message>
        <source>Abort</source>
        <translation>中止</translation>
    </message>
    <message>
        <source>Abort the wall inspection</source>
        <translation>中止罐壁检测</translation>
    </message>
    <message>
        <source>Thickness</source>
        <translation>壁厚</translation>
    </message>
    <message>
        <source>Covered</source>
        <translation>已覆盖</translation>
    </message>
    <message>
        <source>Sub-regions</source>
        <translation>子区域</translation>
    </message>
    <message>
        <source>Plan</source>
        <translation>规划路径</translation>
    </message>
    <message>
        <source>coverage {pct} %</source>
        <translation>覆盖率 {pct} %</translation>
    </message>
    <message>
        <source>repetition {pct} %</source>
        <translation>重复率 {pct} %</translation>
    </message>
    <message>
        <source>inspection {state}</source>
        <translation>检测 {state}</translation>
    </message>
    <message>
        <source>readings {n}</source>
        <translation>读数 {n}</translation>
    </message>
    <message>
        <source> (below {lim} mm)</source>
        <translation>（低于 {lim} mm）</translation>
    </message>
    <message>
        <source>{mm} mm{below} at {where}</source>
        <translation>{mm} mm{below}，位置 {where}</translation>
    </message>
    <message>
        <source>thinnest: </source>
        <translation>最薄处：</translation>
    </message>
    <message>
        <source>Tank wall</source>
        <translation>罐壁</translation>
    </message>
</context>
<context>
    <name>WallView</name>
    <message>
        <source>No wall climber connected</source>
        <translation>未连接爬壁机器人</translation>
    </message>
</context>
<context>
    <name>WheelDisplay</name>
    <message>
        <source>The four wheels as the robot last reported them: steering angle (anticlockwise positive) and rolling speed</source>
        <translation>机器人最近上报的四个车轮：转向角（逆时针为正）和滚动速度</translation>
    </message>
    <message>
        <source>stopped</source>
        <translation>停止</translation>
    </message>
    <message>
        <source>front steer</source>
        <translation>前轮转向</translation>
    </message>
    <message>
        <source>counter-phase</source>
        <translation>反相转向</translation>
    </message>
    <message>
        <source>crab</source>
        <translation>蟹行</translation>
    </message>
    <message>
        <source>turn in place</source>
        <translation>原地转向</translation>
    </message>
    <message>
        <source>no wheel data</source>
        <translation>无车轮数据</translation>
    </message>
    <message>
        <source>mode: %1</source>
        <translation>模式：%1</translation>
    </message>
    <message>
        <source>%1 s ago</source>
        <translation>%1 s 前</translation>
    </message>
    <message>
        <source>%1 min ago</source>
        <translation>%1 min 前</translation>
    </message>
    <message>
        <source>%1 h %2 min ago</source>
        <translation>%1 h %2 min 前</translation>
    </message>
    <message>
        <source>last known %1, %2</source>
        <translation>最后已知 %1，%2</translation>
    </message>
    <message>
        <source>FL</source>
        <translation>左前</translation>
    </message>
    <message>
        <source>FR</source>
        <translation>右前</translation>
    </message>
    <message>
        <source>RL</source>
        <translation>左后</translation>
    </message>
    <message>
        <source>RR</source>
        <translation>右后</translation>
    </message>
    <message>
        <source>%1° · %2 m/s</source>
        <translation>%1° · %2 m/s</translation>
    </message>
    <message>
        <source>Wheels</source>
        <translation>车轮</translation>
    </message>
</context>
<context>
    <name>WindowSettings</name>
    <message>
        <source>Log folder: %1</source>
        <translation>日志文件夹：%1</translation>
    </message>
</context>
</TS>
